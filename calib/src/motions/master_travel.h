// SPDX-License-Identifier: Apache-2.0
#pragma once
// The master's typical travel, for the keyframe rule of the recursive estimator
// (keyframe_pairing.h) in the master's own unit. A monocular master's unit is arbitrary (each
// VO initialisation sets its own), so a keyframe distance in that unit would make the keyframes,
// and with them the calibration, depend on it: the same drive in 1e-6, 1 and 1e6 of a unit gave
// 362, 553 and 1191 keyframes and rotations 3σ apart. Instead a keyframe is due once the master
// has moved as far as its median speed carries it in keyframe_min_travel_s.
//
// The speed is the median of the master's speeds between consecutive sets of one master
// segment over the last window_ns of stream time (robust to a glitched pose and to the noise of
// single steps); a new master segment (a new unit) restarts it. Scaling every master position
// by k scales DistanceIn by k: the keyframes do not depend on the unit.

#include <cstdint>
#include <deque>
#include <optional>

#include "rigcal/base/types.h"

namespace rigcal::internal {

class MasterTravel {
 public:
  explicit MasterTravel(int64_t window_ns) : window_ns_(window_ns) {}

  // The master's pose at set time `t_ns` (increasing) in odometry segment `segment`.
  void Add(int64_t t_ns, const Pose& master, int segment);

  // How far the master travels in `seconds` at its median speed; +infinity while no speed has
  // been measured (the first set of a segment): only rotation and time make keyframes then.
  double DistanceIn(double seconds) const;

 private:
  struct Step {
    int64_t t_ns = 0;
    double speed_per_s = 0.0;  // master units per second
  };
  static constexpr size_t kMaxSteps = 1024;  // bounds the median's work at high set rates

  int64_t window_ns_;
  std::optional<int> segment_;
  int64_t last_t_ns_ = 0;
  Pose last_;
  std::deque<Step> steps_;
};

}  // namespace rigcal::internal
