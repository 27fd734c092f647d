// SPDX-License-Identifier: Apache-2.0
// The level-noise model of consecutive motions' residuals and its whitening
// (rigcal/calib/noise_whitening.h): exact identities of the filter and the maximum-likelihood
// fit on series of known noise, with tolerances from the sampling error.
#include "rigcal/calib/noise_whitening.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>
#include <vector>

namespace rigcal {
namespace {

// Increments of levels y_t = walk + AR(1) + white (t = 0..n, y_0 included and differenced away).
Eigen::VectorXd SimulatedIncrements(int n, const LevelNoise& noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  double x = 0.0;
  double a = std::sqrt(noise.correlated) * g(rng);
  double previous = x + a + std::sqrt(noise.white) * g(rng);
  Eigen::VectorXd d(n);
  const double innovation = std::sqrt(noise.correlated * (1.0 - noise.phi * noise.phi));
  for (int t = 0; t < n; ++t) {
    x += std::sqrt(noise.walk) * g(rng);
    a = noise.phi * a + innovation * g(rng);
    const double y = x + a + std::sqrt(noise.white) * g(rng);
    d(t) = y - previous;
    previous = y;
  }
  return d;
}

// A pure random walk: the innovations are the increments themselves (GLS = OLS on the
// consecutive motions).
TEST(NoiseWhitening, RandomWalkLeavesTheIncrements) {
  LevelNoise walk;
  walk.walk = 4.0;
  Eigen::MatrixXd d(50, 2);
  d.setRandom();
  const Eigen::MatrixXd w = WhitenIncrements(d, walk);
  EXPECT_LT((w - d / 2.0).cwiseAbs().maxCoeff(), 1e-12);
}

// White levels: GLS on the increments equals OLS on the levels with an unknown offset, for any
// regressor (the filter's diffuse start is that offset).
TEST(NoiseWhitening, WhiteLevelsAreLeastSquaresOnTheLevels) {
  const int n = 200;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::VectorXd u(n + 1), y(n + 1);
  for (int t = 0; t <= n; ++t) {
    u(t) = std::sin(0.05 * t) + 0.3 * g(rng);
    y(t) = 2.0 * u(t) + 5.0 + 0.1 * g(rng);
  }
  Eigen::MatrixXd levels(n + 1, 2);
  levels << u, Eigen::VectorXd::Ones(n + 1);
  const Eigen::Vector2d ols = levels.colPivHouseholderQr().solve(y);

  Eigen::MatrixXd inc(n, 2);
  for (int t = 0; t < n; ++t) inc.row(t) << y(t + 1) - y(t), u(t + 1) - u(t);
  LevelNoise white;
  white.white = 0.01;
  const Eigen::MatrixXd w = WhitenIncrements(inc, white);
  const double gls = w.col(1).dot(w.col(0)) / w.col(1).squaredNorm();
  EXPECT_NEAR(gls, ols(0), 1e-9 * std::abs(ols(0)));
}

// The fit recovers a known AR(1) coefficient and the levels of the parts. n = 20000: the
// standard error of phi is ~0.01 here (the white part blurs it), the tolerances are ~5 SE.
TEST(NoiseWhitening, FitRecoversAKnownModel) {
  LevelNoise truth;
  truth.white = 0.2;
  truth.correlated = 1.0;
  truth.phi = 0.8;
  truth.walk = 0.01;
  const std::vector<Eigen::VectorXd> runs = {SimulatedIncrements(10000, truth, 7),
                                             SimulatedIncrements(10000, truth, 8)};
  const LevelNoise fit = FitLevelNoise(runs);
  EXPECT_NEAR(fit.phi, 0.8, 0.05);
  EXPECT_NEAR(fit.correlated, 1.0, 0.3);
  EXPECT_NEAR(fit.white, 0.2, 0.08);
  EXPECT_NEAR(fit.walk, 0.01, 0.01);
  // The true model is at most as likely as the fitted one, and not much less (2 x log-likelihood
  // ratio ~ chi2 with 4 degrees of freedom: below 25 with probability > 0.9999).
  const double l_fit = IncrementLogLikelihood(runs, fit);
  const double l_true = IncrementLogLikelihood(runs, truth);
  EXPECT_GE(l_fit, l_true - 1e-6);
  EXPECT_LT(2.0 * (l_fit - l_true), 25.0);
}

// Whitened with the fitted model, white + random-walk levels give uncorrelated innovations of
// unit variance (within 5 standard errors: 5/sqrt(n) for the lag-1 correlation,
// 5 sqrt(2/n) for the variance).
TEST(NoiseWhitening, FittedModelWhitens) {
  LevelNoise truth;
  truth.white = 1.0;
  truth.walk = 0.05;
  const int n = 8000;
  const Eigen::VectorXd d = SimulatedIncrements(n, truth, 11);
  // The increments themselves are far from white: lag-1 correlation near -0.48.
  const double raw = d.head(n - 1).dot(d.tail(n - 1)) / d.squaredNorm();
  EXPECT_LT(raw, -0.3);
  const LevelNoise fit = FitLevelNoise({d});
  const Eigen::VectorXd w = WhitenIncrements(d, fit).col(0).tail(n - 100);  // past the start
  const int m = static_cast<int>(w.size());
  const double variance = w.squaredNorm() / m;
  const double lag1 = w.head(m - 1).dot(w.tail(m - 1)) / w.squaredNorm();
  EXPECT_NEAR(variance, 1.0, 5.0 * std::sqrt(2.0 / m));
  EXPECT_NEAR(lag1, 0.0, 5.0 / std::sqrt(m));
  // White and an AR(1) part of small phi are alike: their sum is the white level variance.
  EXPECT_NEAR(fit.white + fit.correlated, 1.0, 0.15)
      << "white " << fit.white << " correlated " << fit.correlated << " phi " << fit.phi;
  EXPECT_NEAR(fit.walk, 0.05, 0.02);
}

}  // namespace
}  // namespace rigcal
