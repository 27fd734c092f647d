// SPDX-License-Identifier: Apache-2.0
// Decalibration detection of the recursive estimator (decalibration_check.h).
#include "online/decalibration_check.h"

#include <algorithm>
#include <cmath>

#include "rigcal/base/quaternion.h"

namespace rigcal::internal {

bool ModelSettled(const RigEstimatorOptions& o, int64_t model_changed_ns, int64_t now_ns) {
  return model_changed_ns < 0 ||
         now_ns - model_changed_ns >= static_cast<int64_t>(o.short_half_life_s * 1e9);
}

WindowComparison CompareWindows(const RigEstimatorOptions& o, const SlaveCalibration& long_est,
                                const SlaveCalibration& short_est, double overlap,
                                bool model_settled, int64_t now_ns, DecalibrationState* state) {
  WindowComparison out;
  const double long_sigma = overlap * long_est.rot_std_deg;
  const bool settled = long_est.motions.used >= o.converged_min_motions && long_sigma > 0.0 &&
                       long_sigma <= o.converged_rot_std_deg;
  if (!(settled && model_settled && long_est.solved() && short_est.solved() &&
        !long_est.observability.planar && !short_est.observability.planar &&
        short_est.motions.used >= o.converged_min_motions / 2)) {
    return out;
  }
  out.compared = true;
  const double diff = AngleBetween(long_est.estimate.q, short_est.estimate.q) * kDegPerRad;
  out.rot_diff_deg = diff;
  const double sigma = overlap * std::hypot(long_est.rot_std_deg, short_est.rot_std_deg);
  bool disagree = diff > std::max(o.decalibration_min_deg, o.decalibration_sigmas * sigma);
  if (o.decalibration_min_translation > 0.0 && long_est.position_observable) {
    disagree = disagree || (long_est.estimate.C - short_est.estimate.C).norm() >
                               o.decalibration_min_translation;
  }
  state->disagreements = disagree ? state->disagreements + 1 : 0;
  if (state->disagreements == 1) state->disagree_since_ns = now_ns;
  const auto hold_ns = static_cast<int64_t>(o.decalibration_confirm_s * 1e9);
  if (state->disagreements >= o.decalibration_confirmations &&
      now_ns - state->disagree_since_ns >= hold_ns) {
    out.decalibrated = true;
    state->disagreements = 0;
    state->decalibrated_at_ns = now_ns;
  }
  return out;
}

void FollowRestartedClock(int64_t now_ns, DecalibrationState* state) {
  state->disagree_since_ns = std::min(state->disagree_since_ns, now_ns);
  state->decalibrated_at_ns = std::min(state->decalibrated_at_ns, now_ns);
}

bool RecentlyDecalibrated(const RigEstimatorOptions& o, const DecalibrationState& state,
                          int64_t now_ns) {
  return state.decalibrated_at_ns >= 0 &&
         now_ns - state.decalibrated_at_ns < static_cast<int64_t>(o.short_half_life_s * 1e9);
}

}  // namespace rigcal::internal
