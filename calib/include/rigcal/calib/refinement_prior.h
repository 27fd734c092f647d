// SPDX-License-Identifier: Apache-2.0
#pragma once
// RefinementPrior: the motions a refinement does not hold one by one, as the quadratic forms of
// their linear residuals (made by the recursive estimator's statistics, minimised with a window
// of motions by the non-linear refinement).

#include <Eigen/Core>
#include <vector>

namespace rigcal {

// Everything the statistics know about the motions that are NOT in the refinement window,
// as the exact sums of squared linear residuals of those motions (the residuals the
// refinement minimises, thesis 4.26):
//   sum w |A q|^2 = q^T rotation q                                                  (4.10)
//   sum w |(I - R0) C + λ_s dR C_i - C0|^2 = u^T position u,  u = [C; λ_1 vec(dR); ...; 1]
// with one 9-block per entry of `segments` (the open scale segments, vec column-major).
// Closed segments enter through their Schur complement on C (marginalised at the rotation of
// the time). A window refinement with this prior minimises over every motion since the start
// (or the last reset), not only the window's: the window adds nothing but robust re-weighting.
struct RefinementPrior {
  double weight = 0.0;  // sum of the motions' weights (0: no prior)
  // Sum of the weights of the motions in `position` (the motions since the master odometry
  // last re-initialised; `weight` when it never did): its count of position equations.
  double position_weight = 0.0;
  int motions = 0;  // how many motions
  Eigen::Matrix4d rotation = Eigen::Matrix4d::Zero();
  std::vector<int> segments;
  Eigen::MatrixXd position;  // (4 + 9 * segments.size()) square, positive semi-definite
};

}  // namespace rigcal
