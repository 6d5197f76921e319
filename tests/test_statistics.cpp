// The Mann-Whitney U test against scipy 1.10.1, and the significance marks of the paper's
// figures. Every expected U and p was printed by
//   from scipy.stats import mannwhitneyu
//   r = mannwhitneyu(x, y, alternative='two-sided'); print(repr(r.statistic), repr(r.pvalue))
// under /usr/bin/python3 with scipy 1.10.1 (default method='auto'), x and y as in the test.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "lazyboe/common/statistics.h"

namespace lazyboe {
namespace {

// U exactly, p to 1e-9 relative; u1 + u2 = |x| |y|.
void expect_scipy(const std::vector<double>& x, const std::vector<double>& y, double u1, double p) {
  const MannWhitney r = mann_whitney_u(x, y);
  EXPECT_EQ(r.u1, u1);
  EXPECT_EQ(r.u2, static_cast<double>(x.size() * y.size()) - u1);
  EXPECT_NEAR(r.p, p, 1e-9 * p);
  // Swapping the samples swaps the statistics and keeps p.
  const MannWhitney s = mann_whitney_u(y, x);
  EXPECT_EQ(s.u1, r.u2);
  EXPECT_EQ(s.u2, r.u1);
  EXPECT_NEAR(s.p, p, 1e-9 * p);
}

// Exact distribution: sizes 5 and 6, no ties.
TEST(MannWhitney, SmallSamplesExact) {
  expect_scipy({0.82, 1.31, 0.47, 2.05, 1.12}, {1.94, 2.71, 1.58, 3.40, 2.26, 0.95}, 5.0,
               0.08225108225108226);
}

// Normal approximation with tie correction: times to first solution capped at a 60 s budget.
TEST(MannWhitney, MediumSamplesWithTies) {
  expect_scipy({1.2, 0.8, 60,  2.5, 1.2, 0.6, 3.1, 60,  0.9, 1.7, 2.5, 0.8, 1.1,
                4.2, 1.2, 0.7, 60,  2.0, 1.5, 0.9, 3.3, 1.1, 0.8, 2.5, 1.9},
               {4.1, 60,  2.5, 60, 7.3, 3.9, 60, 12.0, 5.5, 2.5, 60,   9.1, 3.3,
                60,  6.2, 4.4, 60, 1.2, 8.8, 60, 5.5,  3.0, 60,  10.4, 2.2},
               96.0, 2.4733210161651664e-05);
}

// Identical samples share every value, so ties: normal approximation, p clipped to 1.
TEST(MannWhitney, IdenticalSamples) { expect_scipy({1, 2, 3, 4, 5}, {1, 2, 3, 4, 5}, 12.5, 1.0); }

// A single value everywhere: the tie-corrected variance is 0 and p is 1.
TEST(MannWhitney, AllValuesEqual) { expect_scipy({2, 2, 2}, {2, 2}, 3.0, 1.0); }

TEST(MannWhitney, SeparatedSamplesExact) {
  expect_scipy({1, 2, 3, 4, 5}, {6, 7, 8, 9, 10}, 0.0, 0.007936507936507936);
}

TEST(MannWhitney, SeparatedSamplesAsymptotic) {
  std::vector<double> x, y;
  for (int i = 0; i < 30; ++i) {
    x.push_back(i);
    y.push_back(100 + i);
  }
  expect_scipy(x, y, 0.0, 3.019859359162157e-11);
}

TEST(MannWhitney, UnequalSizesExact) {
  expect_scipy({5.5, 0.25, 9.75}, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12}, 14.0,
               0.6329670329670329);
}

// scipy's 'auto' takes the exact distribution while either sample has at most 8 values.
TEST(MannWhitney, UnequalSizesExactOneLongSample) {
  std::vector<double> y;
  for (int i = 0; i < 60; ++i) y.push_back(0.1 * i);
  expect_scipy({0.25, 0.75, 1.25, 1.75}, y, 42.0, 0.02763088313061872);
}

TEST(MannWhitney, UnequalSizesWithTies) {
  expect_scipy({3, 1, 4, 1, 5, 9, 2, 6, 5, 3},
               {2, 7, 1, 8, 2, 8, 1, 8, 2, 8, 4, 5, 9, 0, 4, 5, 2, 3, 5, 3,
                6, 0, 2, 8, 7, 4, 7, 1, 3, 5, 2, 6, 6, 2, 4, 9, 7, 7, 5, 7},
               167.0, 0.4275443121102861);
}

// Sizes 8 and 9: exact (one sample has 8 values); 9 and 9: normal approximation.
TEST(MannWhitney, ExactAsymptoticBoundary) {
  const std::vector<double> y = {1, 3, 5, 7, 9, 11, 13, 15, 17};
  expect_scipy({0.5, 2.5, 4.5, 6.5, 8.5, 10.5, 12.5, 1.75}, y, 22.0, 0.1995886466474702);
  expect_scipy({0.5, 2.5, 4.5, 6.5, 8.5, 10.5, 12.5, 1.75, 3.25}, y, 24.0, 0.1577043874630777);
}

TEST(MannWhitney, SingleValues) { expect_scipy({1}, {2}, 0.0, 1.0); }

// scipy raises for an empty sample; here U is 0 and p is NaN.
TEST(MannWhitney, EmptySample) {
  for (const MannWhitney& r :
       {mann_whitney_u({}, {1, 2}), mann_whitney_u({1, 2}, {}), mann_whitney_u({}, {})}) {
    EXPECT_EQ(r.u1, 0.0);
    EXPECT_EQ(r.u2, 0.0);
    EXPECT_TRUE(std::isnan(r.p));
  }
}

// As scipy's default nan_policy='propagate': everything NaN.
TEST(MannWhitney, NanPropagates) {
  const MannWhitney r = mann_whitney_u({1, NAN}, {2, 3});
  EXPECT_TRUE(std::isnan(r.u1));
  EXPECT_TRUE(std::isnan(r.u2));
  EXPECT_TRUE(std::isnan(r.p));
}

TEST(SignificanceMark, Boundaries) {
  EXPECT_STREQ(significance_mark(1.0), "ns");
  EXPECT_STREQ(significance_mark(0.0529), "ns");
  EXPECT_STREQ(significance_mark(std::nextafter(0.05, 1.0)), "ns");
  EXPECT_STREQ(significance_mark(0.05), "*");
  EXPECT_STREQ(significance_mark(std::nextafter(0.01, 1.0)), "*");
  EXPECT_STREQ(significance_mark(0.01), "**");
  EXPECT_STREQ(significance_mark(std::nextafter(0.001, 1.0)), "**");
  EXPECT_STREQ(significance_mark(0.001), "***");
  EXPECT_STREQ(significance_mark(std::nextafter(0.0001, 1.0)), "***");
  EXPECT_STREQ(significance_mark(0.0001), "****");
  EXPECT_STREQ(significance_mark(0.0), "****");
  EXPECT_STREQ(significance_mark(NAN), "n/a");
}

TEST(FormatPValue, FourDecimalsOrScientific) {
  EXPECT_EQ(format_p_value(0.05291), "0.0529");
  EXPECT_EQ(format_p_value(1.0), "1.0000");
  EXPECT_EQ(format_p_value(1e-4), "0.0001");
  EXPECT_EQ(format_p_value(2.4733210161651664e-05), "2.5e-05");
  EXPECT_EQ(format_p_value(0.0), "0.0e+00");
  EXPECT_EQ(format_p_value(NAN), "n/a");
}

}  // namespace
}  // namespace lazyboe
