// SPDX-License-Identifier: Apache-2.0
#pragma once
// Errors in the variables of C's regressor in (4.14): (I - R_0^k) ΔC with R_0^k measured. The
// rotation's noise E_k enters the regressor, and the normal matrix of C grows by E[Σ E_kᵀ E_k]
// (after whitening) in expectation, which shrinks the least-squares C towards 0 in proportion
// to the rotation noise over the rotation of the motions (attenuation; 1.15 % of a 2.2 units
// long C on VO-like drift of 0.1°/frame at 30 Hz). GLS subtracts the expected term from its
// normal matrix (corrected least squares), which removes this part of the bias to first order.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "rigcal/calib/noise_whitening.h"

namespace rigcal::internal {

struct RegressorNoiseInput {
  // Per motion, in time order: the regressor's rotation times C's coordinates, G_k T
  // (run frame; columns beyond the free coordinates zero): a rotation error δ_k (run frame)
  // changes the motion's position row by -[δ_k]× G_k T.
  std::vector<Eigen::Matrix3d> lever;
  std::vector<int> run_start;  // first motion of every run, ascending, then motions.size()
  // The rotation error of the regressor per run-frame component (increments of a level), and
  // the noise the position rows are whitened with.
  LevelNoise rotation[3];
  LevelNoise position[3];
  int samples = 16;  // Monte Carlo draws of the rotation errors
  uint64_t seed = 1;
};

// Per motion, E[Ẽ_kᵀ Ẽ_k] of the whitened regressor noise Ẽ (row k of every position
// component), estimated from `samples` draws: their sum is the term to subtract from the
// normal matrix of C's coordinates.
std::vector<Eigen::Matrix3d> RegressorNoiseGram(const RegressorNoiseInput& input);

}  // namespace rigcal::internal
