#include "lazyboe/common/statistics.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <numeric>

namespace lazyboe {

namespace {

// Average ranks (1-based) of the values of x followed by y; tie_term = sum of t^3 - t over
// groups of t equal values.
struct Ranking {
  double rank_sum_x = 0;
  double tie_term = 0;
};

Ranking rank(const std::vector<double>& x, const std::vector<double>& y) {
  std::vector<double> xy(x);
  xy.insert(xy.end(), y.begin(), y.end());
  std::vector<size_t> order(xy.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return xy[a] < xy[b]; });
  Ranking r;
  for (size_t i = 0; i < order.size();) {
    size_t j = i + 1;
    while (j < order.size() && xy[order[j]] == xy[order[i]]) ++j;
    const double average = 0.5 * static_cast<double>(i + 1 + j);  // ranks i+1 .. j
    const double t = static_cast<double>(j - i);
    r.tie_term += t * t * t - t;
    for (size_t k = i; k < j; ++k)
      if (order[k] < x.size()) r.rank_sum_x += average;
    i = j;
  }
  return r;
}

// P(U >= u) * 2 under the null hypothesis for samples of sizes n1, n2 without ties, as scipy's
// _MWU.sf: the number of arrangements with U = k (Di Bucchianico's recurrence
// f(m, n, k) = f(m - 1, n, k - n) + f(m, n - 1, k)), summed over k <= n1 * n2 - u and divided
// by the number of all arrangements.
double exact_two_sided_p(double u, size_t n1, size_t n2) {
  const size_t m = std::min(n1, n2), n = std::max(n1, n2);  // f is symmetric in m and n
  const size_t last = static_cast<size_t>(static_cast<double>(m * n) - u);
  // f[j][k] = f(j, columns, k) for j <= m, k <= last; columns = 0 to begin with.
  std::vector<std::vector<double>> f(m + 1, std::vector<double>(last + 1, 0.0));
  for (size_t j = 0; j <= m; ++j) f[j][0] = 1.0;
  for (size_t columns = 1; columns <= n; ++columns)
    for (size_t j = 1; j <= m; ++j)  // row j - 1 already holds f(j - 1, columns, .)
      for (size_t k = columns; k <= last; ++k) f[j][k] += f[j - 1][k - columns];
  double all = 1.0;  // binomial(m + n, m), exact while it fits a double's mantissa
  for (size_t i = 1; i <= m; ++i) all = all * static_cast<double>(n + i) / static_cast<double>(i);
  double sf = 0.0;
  for (size_t k = 0; k <= last; ++k) sf += f[m][k] / all;
  return std::min(1.0, 2.0 * sf);
}

// Standard normal CDF, computed as scipy's special.ndtr (cephes).
double ndtr(double a) {
  const double x = a * M_SQRT1_2, z = std::fabs(x);
  if (z < M_SQRT1_2) return 0.5 + 0.5 * std::erf(x);
  const double y = 0.5 * std::erfc(z);
  return x > 0 ? 1.0 - y : y;
}

}  // namespace

MannWhitney mann_whitney_u(const std::vector<double>& x, const std::vector<double>& y) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto is_nan = [](double v) { return std::isnan(v); };
  if (std::any_of(x.begin(), x.end(), is_nan) || std::any_of(y.begin(), y.end(), is_nan))
    return {nan, nan, nan};
  if (x.empty() || y.empty()) return {0.0, 0.0, nan};

  const size_t n1 = x.size(), n2 = y.size();
  const double n1d = static_cast<double>(n1), n2d = static_cast<double>(n2);
  const Ranking r = rank(x, y);
  const double u1 = r.rank_sum_x - n1d * (n1d + 1) / 2;
  const double u2 = n1d * n2d - u1;
  const double u = std::max(u1, u2);

  const bool exact = (n1 <= 8 || n2 <= 8) && r.tie_term == 0;
  if (exact) return {u1, u2, exact_two_sided_p(u, n1, n2)};

  const double n = n1d + n2d;
  const double s = std::sqrt(n1d * n2d / 12 * ((n + 1) - r.tie_term / (n * (n - 1))));
  const double z = (u - n1d * n2d / 2 - 0.5) / s;  // continuity correction; -inf if all tied
  const double p = 2.0 * ndtr(-z);
  return {u1, u2, std::clamp(p, 0.0, 1.0)};
}

const char* significance_mark(double p) {
  if (std::isnan(p)) return "n/a";
  if (p <= 1e-4) return "****";
  if (p <= 1e-3) return "***";
  if (p <= 1e-2) return "**";
  if (p <= 5e-2) return "*";
  return "ns";
}

std::string format_p_value(double p) {
  if (std::isnan(p)) return "n/a";
  char text[32];
  std::snprintf(text, sizeof text, p < 1e-4 ? "%.1e" : "%.4f", p);
  return text;
}

}  // namespace lazyboe
