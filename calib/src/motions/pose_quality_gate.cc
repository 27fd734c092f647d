// SPDX-License-Identifier: Apache-2.0
// The online gate on poorly tracked poses (pose_quality_gate.h).
#include "motions/pose_quality_gate.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {

PoseQualityGate::PoseQualityGate(int cameras, QualityGateOptions options)
    : options_(options), cameras_(static_cast<size_t>(std::max(cameras, 0))) {}

void PoseQualityGate::Accept(Camera* c, double quality) const {
  if (c->window.full()) c->window.PopFront();
  c->window.PushBack() = quality;
  c->rejected_in_row = 0;
  if (!c->window.full()) return;
  std::vector<double> values(c->window.size());
  for (size_t i = 0; i < values.size(); ++i) values[i] = c->window[i];
  const RobustStats stats = MedianAndSigma(std::move(values));
  c->threshold =
      stats.median - std::max(options_.sigmas * stats.sigma, options_.drop * stats.median);
}

std::vector<bool> PoseQualityGate::Check(const std::vector<std::optional<CameraPose>>& poses) {
  std::vector<bool> poor(poses.size(), false);
  for (size_t i = 0; i < poses.size() && i < cameras_.size(); ++i) {
    if (!poses[i] || !std::isfinite(poses[i]->quality)) continue;
    Camera& c = cameras_[i];
    const double quality = poses[i]->quality;
    if (c.window.full() && quality < c.threshold) {
      if (++c.rejected_in_row < kWindow) {
        poor[i] = true;
        continue;
      }
      while (!c.window.empty()) c.window.PopFront();  // the camera changed for good
    }
    Accept(&c, quality);
  }
  return poor;
}

double PoseQualityGate::Threshold(int camera) const {
  const Camera& c = cameras_.at(static_cast<size_t>(camera));
  return c.window.full() ? c.threshold : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace rigcal::internal
