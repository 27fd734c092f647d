// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pose noise of a series of consecutive motions' residuals, and its whitening for
// generalised least squares (GLS).
//
// A residual component of the motions (k, k+1) is the increment of a pose-level error: the
// sum of the increments since the start of a run ("level") is white pose noise (motion
// capture, PnP), plus AR(1)-correlated noise (tracking with memory), plus a random walk
// (odometry drift). Every fixed span's motion is a sum of such increments, so the GLS
// estimate on the increments with this noise is at least as good as any span's.
//
// The model is a state-space model of the level y_t = x_t + a_t + w_t: x a random walk
// (diffuse start: the level's offset is unknown), a stationary AR(1), w white. Its Kalman
// filter turns the increments into independent innovations of unit variance; the filter is
// linear and its gains do not depend on the data, so the same recursion whitens the
// residuals and the columns of their Jacobian. White pose noise makes the increments an MA(1)
// series with a unit root, which no AR(p) prewhitening of moderate order removes at the low
// frequencies where the calibration signal lies; the state-space filter is exact there.

#include <Eigen/Core>
#include <atomic>
#include <vector>

namespace rigcal {

struct LevelNoise {
  double white = 0.0;       // variance of the white part
  double correlated = 0.0;  // stationary variance of the AR(1) part
  double phi = 0.0;         // its lag-1 coefficient, |phi| < 1
  double walk = 0.0;        // variance of a step of the random walk
};

// The increments of one run (rows in time order; columns: residual, Jacobian columns, ...)
// whitened: row t is the innovation of the level after increment t over its standard
// deviation. Every row of the result has unit variance and rows are independent when the
// first column's errors follow `noise`. The level before the first increment is 0 and its
// offset unknown (diffuse), so a constant added to every level changes nothing.
Eigen::MatrixXd WhitenIncrements(const Eigen::MatrixXd& increments, const LevelNoise& noise);

// Gaussian log-likelihood of runs of increments (each a vector in time order) under `noise`.
double IncrementLogLikelihood(const std::vector<Eigen::VectorXd>& runs, const LevelNoise& noise);

// Maximum-likelihood noise of runs of increments (Nelder-Mead on the logarithms of the
// variances and atanh(phi), from a few starts). Variances are at least 1e-8 of the increments'
// variance, so the filter never divides by zero. `cancel` (CalibrationOptions::cancel) set: the
// fit ends within a few evaluations of the likelihood, its result of no use.
LevelNoise FitLevelNoise(const std::vector<Eigen::VectorXd>& runs,
                         const std::atomic<bool>* cancel = nullptr);

}  // namespace rigcal
