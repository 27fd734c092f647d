// SPDX-License-Identifier: Apache-2.0
// The batch calibrator's length unit (batch_units.h).
#include "batch/batch_units.h"

#include <cmath>

namespace rigcal::internal {

double LengthUnitOf(const RigRecording& recording) {
  const std::vector<Pose>& poses = recording.master.poses;
  if (poses.empty()) return 1.0;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Pose& p : poses) mean += p.C;
  mean /= static_cast<double>(poses.size());
  double sum = 0.0;
  for (const Pose& p : poses) sum += (p.C - mean).squaredNorm();
  const double rms = std::sqrt(sum / static_cast<double>(poses.size()));
  if (!std::isfinite(rms) || !(rms > 0.0)) return 1.0;
  const double unit = std::exp2(std::round(std::log2(rms)));
  return std::isfinite(unit) && unit > 0.0 ? unit : 1.0;
}

RigRecording InLengthUnit(const RigRecording& recording, double length) {
  if (length == 1.0) return recording;
  RigRecording out = recording;
  for (Pose& p : out.master.poses) p.C /= length;
  for (CameraTrack& slave : out.slaves) {
    for (Pose& p : slave.poses) p.C /= length;
  }
  return out;
}

CalibrationOptions InLengthUnit(const CalibrationOptions& options, double length) {
  if (length == 1.0) return options;
  CalibrationOptions out = options;
  for (auto& [name, nominal] : out.nominal) nominal.C /= length;
  out.nominal_sigma /= length;
  out.scale_dot_epsilon /= length;
  return out;
}

void FromLengthUnit(double length, SlaveCalibration* r) {
  if (length == 1.0) return;
  r->estimate.C *= length;
  r->pos_std *= length;
  r->axis_offset_std *= length;
}

}  // namespace rigcal::internal
