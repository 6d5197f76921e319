#include "lazyboe/common/histogram.h"

#include <algorithm>
#include <cstdio>
#include <numeric>

namespace lazyboe {

std::string text_histogram(const std::vector<double>& values, double lo, double hi, int bins,
                           int bar_width, const std::string& indent) {
  std::vector<size_t> counts(bins, 0);
  for (double v : values) {
    int b = hi > lo ? static_cast<int>((v - lo) / (hi - lo) * bins) : 0;
    counts[std::clamp(b, 0, bins - 1)]++;
  }
  const size_t peak = std::max<size_t>(1, *std::max_element(counts.begin(), counts.end()));
  std::string out;
  char line[160];
  for (int b = 0; b < bins; ++b) {
    const double a = lo + (hi - lo) * b / bins, z = lo + (hi - lo) * (b + 1) / bins;
    const int len = static_cast<int>(static_cast<double>(counts[b]) / peak * bar_width + 0.5);
    std::snprintf(line, sizeof line, "%s[%7.3f, %7.3f%c %8zu  %s\n", indent.c_str(), a, z,
                  b + 1 == bins ? ']' : ')', counts[b], std::string(len, '#').c_str());
    out += line;
  }
  return out;
}

Quantiles quantiles(std::vector<double> v) {
  Quantiles q;
  if (v.empty()) return q;
  std::sort(v.begin(), v.end());
  // Linear interpolation between the closest ranks (numpy's default): the median of an even
  // count is the mean of the middle two.
  auto at = [&](double f) {
    const double pos = f * (v.size() - 1);
    const size_t lo = static_cast<size_t>(pos);
    return lo + 1 < v.size() ? v[lo] + (pos - lo) * (v[lo + 1] - v[lo]) : v[lo];
  };
  q.min = v.front();
  q.p10 = at(0.1);
  q.median = at(0.5);
  q.p90 = at(0.9);
  q.max = v.back();
  q.mean = std::accumulate(v.begin(), v.end(), 0.0) / v.size();
  return q;
}

}  // namespace lazyboe
