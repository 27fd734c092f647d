// SPDX-License-Identifier: Apache-2.0
// The σ floor of auto and gls batch results (batch_sigma_floor.h).
#include "batch/batch_sigma_floor.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "batch/batch_gls.h"
#include "noise/time_blocks.h"
#include "refinement/gls_refinement.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// Raises a known (finite) `*sigma` to sqrt(sigma_gls² + d²) when that is larger; an unknown σ
// stays unknown.
bool Raise(double sigma_gls, double difference, double* sigma) {
  const double floor = std::hypot(sigma_gls, difference);
  if (!std::isfinite(*sigma) || !std::isfinite(floor) || !(floor > *sigma)) return false;
  *sigma = floor;
  return true;
}

}  // namespace

void HoldSigmaToConsecutiveGls(const RigRecording& recording, int slave,
                               const CalibrationOptions& options, SlaveCalibration* r) {
  if (!r->solved() || r->scale_model == ScaleModel::kPartitions || !options.compute_covariance ||
      options.covariance_time_blocks <= 0) {
    return;
  }
  const std::vector<MotionData> motions = ChainMotions(recording, slave, 1, *r);
  GlsInput in = GlsStartOf(*r, options);
  in.time_blocks = BlocksForDurations(motions, options.covariance_time_blocks);
  const GlsResult g = RefineGls(motions, in);
  if (!g.ok) return;
  SlaveCalibration efficient = *r;
  TakeGls(g, in, options, &efficient);
  bool raised = false;
  const double d_deg = AngleBetween(efficient.estimate.q, r->estimate.q) * kDegPerRad;
  raised |= Raise(efficient.rot_std_deg, d_deg, &r->rot_std_deg);
  if (!in.translational) {
    const Eigen::Vector3d d = efficient.estimate.C - r->estimate.C;
    for (int a = 0; a < 3; ++a) raised |= Raise(efficient.pos_std[a], d[a], &r->pos_std[a]);
    const Eigen::Vector3d& axis = r->observability.planar_axis;
    raised |= Raise(efficient.axis_offset_std, axis.dot(d), &r->axis_offset_std);
  }
  for (size_t s = 0; s < r->scales.size() && s < efficient.scales.size(); ++s) {
    const double d = efficient.scales[s].scale - r->scales[s].scale;
    raised |= Raise(efficient.scales[s].std, d, &r->scales[s].std);
  }
  if (raised) {
    r->message += "; sigma raised to that of generalised least squares on the " +
                  std::to_string(g.increments) +
                  " consecutive motions with its difference from this estimate";
  }
}

}  // namespace rigcal::internal
