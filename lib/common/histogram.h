// Text histograms for tool summaries.
#pragma once

#include <string>
#include <vector>

namespace lazyboe {

// One line per bin: "[lo, hi)  count  ####". Values outside [lo, hi] go to the end bins.
std::string text_histogram(const std::vector<double>& values, double lo, double hi, int bins,
                           int bar_width = 40, const std::string& indent = "  ");

struct Quantiles {
  double min = 0, p10 = 0, median = 0, p90 = 0, max = 0, mean = 0;
};
Quantiles quantiles(std::vector<double> values);

}  // namespace lazyboe
