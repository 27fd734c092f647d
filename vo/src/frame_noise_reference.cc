// SPDX-License-Identifier: Apache-2.0
// The camera's usual track noise and a frame's factor in the pose quality
// (frame_noise_reference.h).
#include "frame_noise_reference.h"

#include <algorithm>
#include <cmath>

#include "rigcal/base/robust_statistics.h"

namespace rigcal::vo {

double FrameNoiseReference::UsualSigmaPx() const {
  if (ring_.empty()) return 0.0;
  const RobustStats usual = MedianAndSigma(ring_);
  return usual.median + kSpreadSigmas * usual.sigma;
}

double FrameNoiseReference::Add(double frame_sigma_px) {
  if (!(frame_sigma_px > 0.0) || !std::isfinite(frame_sigma_px)) return 1.0;
  const double usual = UsualSigmaPx();
  if (ring_.size() < static_cast<size_t>(kFrames)) {
    ring_.push_back(frame_sigma_px);
  } else {
    ring_[next_] = frame_sigma_px;
    next_ = (next_ + 1) % ring_.size();
  }
  if (!(usual > 0.0)) return 1.0;
  const double ratio = usual / frame_sigma_px;
  return std::min(1.0, ratio * ratio);
}

}  // namespace rigcal::vo
