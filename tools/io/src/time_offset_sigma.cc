// SPDX-License-Identifier: Apache-2.0
// PropagateTimeOffsetSigma: the estimated clock offsets' σ in the extrinsics' and scales' σ
// (time_offset.h).
#include <cmath>
#include <optional>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/io/time_offset.h"
#include "rigcal/io/trajectory_interpolation.h"

namespace rigcal::io {
namespace {

// The calibration with every estimated offset moved by `sign` times its σ (the others as given).
Expected<RigCalibration> CalibrateAtShiftedOffsets(const TimedTrajectory& master,
                                                   const std::vector<TimedTrajectory>& slaves,
                                                   const OffsetMatch& match, double sign,
                                                   int64_t tolerance_ns,
                                                   const CalibrationOptions& options) {
  std::vector<int64_t> offsets_ns;
  for (const TimeOffsetEstimate& o : match.offsets) {
    const double shift = std::isfinite(o.std_s) ? sign * o.std_s : 0.0;
    offsets_ns.push_back(std::llround((o.offset_s + shift) * 1e9));
  }
  auto matched = MatchFreeRunning(master, slaves, offsets_ns, tolerance_ns);
  if (!matched) return Error{matched.error()};
  return CalibrateRig(*matched, options);
}

// `s`'s σ with the change from `minus` to `plus` (±σ of the offset) added in quadrature: half the
// rotation angle between them (to the largest-axis σ), half the change of C per axis and of each
// scale.
void AddOffsetSensitivity(const SlaveCalibration& plus, const SlaveCalibration& minus,
                          SlaveCalibration* s) {
  auto add = [](double sigma, double change) {
    return std::isfinite(sigma) ? std::hypot(sigma, change) : sigma;
  };
  const double rot_deg = 0.5 * AngleBetween(plus.estimate.q, minus.estimate.q) * kDegPerRad;
  s->rot_std_deg = add(s->rot_std_deg, rot_deg);
  const Eigen::Vector3d dC = 0.5 * (plus.estimate.C - minus.estimate.C);
  for (int a = 0; a < 3; ++a) s->pos_std[a] = add(s->pos_std[a], dC[a]);
  if (std::isfinite(s->axis_offset_std)) {
    const Eigen::Vector3d& axis = s->observability.planar_axis;
    s->axis_offset_std = add(s->axis_offset_std, std::abs(axis.dot(dC)));
  }
  for (SegmentScale& sc : s->scales) {
    for (size_t k = 0; k < plus.scales.size() && k < minus.scales.size(); ++k) {
      if (plus.scales[k].segment != sc.segment || minus.scales[k].segment != sc.segment) continue;
      sc.std = add(sc.std, 0.5 * (plus.scales[k].scale - minus.scales[k].scale));
    }
  }
}

}  // namespace

Status PropagateTimeOffsetSigma(const TimedTrajectory& master,
                                const std::vector<TimedTrajectory>& slaves,
                                const OffsetMatch& match, int64_t tolerance_ns,
                                const CalibrationOptions& options, RigCalibration* result) {
  bool any = false;
  for (const TimeOffsetEstimate& o : match.offsets) any = any || std::isfinite(o.std_s);
  if (!any) return Status::Ok();
  auto plus = CalibrateAtShiftedOffsets(master, slaves, match, +1.0, tolerance_ns, options);
  if (!plus) return Error{plus.error()};
  auto minus = CalibrateAtShiftedOffsets(master, slaves, match, -1.0, tolerance_ns, options);
  if (!minus) return Error{minus.error()};
  for (size_t i = 0; i < result->slaves.size() && i < match.offsets.size(); ++i) {
    SlaveCalibration& s = result->slaves[i];
    if (!std::isfinite(match.offsets[i].std_s) || !s.solved() || i >= plus->slaves.size() ||
        i >= minus->slaves.size() || !plus->slaves[i].solved() || !minus->slaves[i].solved()) {
      continue;
    }
    AddOffsetSensitivity(plus->slaves[i], minus->slaves[i], &s);
  }
  return Status::Ok();
}

}  // namespace rigcal::io
