// SPDX-License-Identifier: Apache-2.0
// The state flags of the recursive estimator's published estimate (convergence_check.h).
#include "online/convergence_check.h"

#include <algorithm>
#include <cmath>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_estimate.h"

namespace rigcal::internal {

uint32_t ConvergenceCheck(const RigEstimatorOptions& o, SlaveCalibration* out,
                          const SlaveCalibration& linear, double rot_factor, bool decalibrated,
                          double master_motion_length, ConvergenceState* s) {
  const SlaveCalibration& published = *out;
  if (!published.solved()) {
    out->state = decalibrated ? SlaveState::kDecalibrated : SlaveState::kInitialising;
    return 0;
  }
  uint32_t flags = 0;
  const double change = AngleBetween(linear.estimate.q, s->last_q) * kDegPerRad;
  s->stable = change <= std::max(rot_factor * linear.rot_std_deg, 0.01) ? s->stable + 1 : 0;
  s->last_q = linear.estimate.q;
  if (published.motion_model == MotionModel::kTranslational) flags |= kFlagTranslationalOnly;
  if (published.observability.planar) flags |= kFlagPlanar;
  // A length in the master's unit: |C|, or the master's motions where the cameras sit close
  // together (a fraction of |C| → 0 would never be reached).
  const double c_ref = std::max(master_motion_length, published.estimate.C.norm());
  // σ must be known (finite): an unknown σ (NaN) has not settled.
  const bool position_ok = !published.position_observable || published.observability.planar ||
                           (published.pos_std.allFinite() &&
                            published.pos_std.maxCoeff() <= o.converged_pos_std_fraction * c_ref);
  const bool rotation_ok =
      std::isfinite(published.rot_std_deg) && published.rot_std_deg <= o.converged_rot_std_deg;
  if (published.motions.used >= o.converged_min_motions && rotation_ok && position_ok &&
      s->stable >= o.converged_stable_keyframes && !decalibrated) {
    out->state = SlaveState::kConverged;
  } else {
    out->state = decalibrated ? SlaveState::kDecalibrated : SlaveState::kUsable;
  }
  return flags;
}

}  // namespace rigcal::internal
