// Significance testing for benchmark summaries (the LazyBoE paper's Evaluation section).
// For medians and means use quantiles() in common/histogram.h.
#pragma once

#include <string>
#include <vector>

namespace lazyboe {

struct MannWhitney {
  double u1;  // U statistic of the first sample x
  double u2;  // U statistic of the second sample y; u1 + u2 = x.size() * y.size()
  double p;   // two-sided p-value
};

// Two-sided Mann-Whitney U test of x against y. Reproduces scipy 1.10
// scipy.stats.mannwhitneyu(x, y, alternative='two-sided') with its default method='auto':
//  - ranks are average ranks, so tied values share their mean rank;
//  - when at least one sample has at most 8 values and no value occurs twice (in x and y
//    together), p comes from the exact distribution of U;
//  - otherwise from the normal approximation with tie correction and continuity correction.
// Where scipy raises, this returns instead:
//  - x or y empty: u1 = u2 = 0 and p = NaN;
//  - a NaN in x or y: u1 = u2 = p = NaN (scipy's default nan_policy='propagate').
// The exact distribution costs O(min^2 * max^2) time for sample sizes min <= 8 and max.
MannWhitney mann_whitney_u(const std::vector<double>& x, const std::vector<double>& y);

// Significance mark as in the paper's figures (statannotations): "****" for p <= 0.0001,
// "***" for p <= 0.001, "**" for p <= 0.01, "*" for p <= 0.05, "ns" above, "n/a" for NaN.
const char* significance_mark(double p);

// p for a summary table: "n/a" for NaN, four decimals from 1e-4 up ("0.0529", "1.0000"),
// otherwise two significant digits ("2.5e-05").
std::string format_p_value(double p);

}  // namespace lazyboe
