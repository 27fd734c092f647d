// SPDX-License-Identifier: Apache-2.0
// The one piece of math of the saved estimator state: direction moments of version-2 states.
#include "rigcal/calib/estimator_state.h"

#include "models/linear_solvers.h"

namespace rigcal {

Eigen::Matrix3d DirectionMomentsFromCrossMoments(const Eigen::Matrix3d& s_dir, double weight) {
  const Eigen::Matrix3d sd = s_dir * internal::SolveAbsoluteOrientation(s_dir).toRotationMatrix();
  const double trace = sd.trace();
  if (!(trace > 0.0)) return Eigen::Matrix3d::Zero();
  return (sd + sd.transpose()) / 2.0 * (weight / trace);
}

}  // namespace rigcal
