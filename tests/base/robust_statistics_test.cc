// SPDX-License-Identifier: Apache-2.0
// Tests of robust_statistics.h: medians, quantiles, the MAD-based sigma and RMS.
#include "rigcal/base/robust_statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace rigcal {
namespace {

TEST(UpperMedian, MiddleOrUpperMiddleValue) {
  EXPECT_EQ(UpperMedian(std::vector<double>{3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(UpperMedian(std::vector<double>{4.0, 1.0, 3.0, 2.0}), 3.0);  // upper of 2, 3
  EXPECT_EQ(UpperMedian(std::vector<int64_t>{50, 10, 40, 20}), 40);
  EXPECT_EQ(UpperMedian(std::vector<double>{}), 0.0);
  EXPECT_EQ(UpperMedian(std::vector<double>{7.0}), 7.0);
}

TEST(Quantile, RankOfFloorPn) {
  const std::vector<double> v = {5, 1, 4, 2, 3, 9, 8, 7, 6, 10};
  EXPECT_EQ(Quantile(v, 0.0), 1.0);
  EXPECT_EQ(Quantile(v, 0.5), UpperMedian(v));
  EXPECT_EQ(Quantile(v, 0.95), 10.0);  // rank 9
  EXPECT_EQ(Quantile(v, 1.0), 10.0);   // clamped to the maximum
  EXPECT_EQ(Quantile(std::vector<double>{}, 0.5), 0.0);
}

TEST(Median, AveragesTheMiddlePair) {
  EXPECT_EQ(Median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_EQ(Median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_EQ(Median({}), 0.0);
}

TEST(MedianAndSigma, IgnoresOutliers) {
  // |x - 3| = 2 1 0 1 97: MAD 1.
  const RobustStats s = MedianAndSigma({1.0, 2.0, 3.0, 4.0, 100.0});
  EXPECT_EQ(s.median, 3.0);
  EXPECT_DOUBLE_EQ(s.sigma, 1.4826);
  const RobustStats none = MedianAndSigma({});
  EXPECT_EQ(none.median, 0.0);
  EXPECT_EQ(none.sigma, 0.0);
  // For normal samples the robust sigma estimates the standard deviation.
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(10.0, 2.0);
  std::vector<double> samples(20000);
  for (double& x : samples) x = normal(rng);
  const RobustStats g = MedianAndSigma(samples);
  EXPECT_NEAR(g.median, 10.0, 0.05);
  EXPECT_NEAR(g.sigma, 2.0, 0.05);
}

TEST(Rms, RootMeanSquareInOrder) {
  EXPECT_EQ(Rms({3.0, 4.0}), std::sqrt(12.5));
  EXPECT_EQ(Rms({-2.0}), 2.0);
  EXPECT_EQ(Rms({}), 0.0);
}

}  // namespace
}  // namespace rigcal
