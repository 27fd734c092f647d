// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 1 of the recursive estimator (RigEstimator): keyframes and the motion pair of each new
// keyframe. The rig constraint T_0^{a->b} dT = dT T_i^{a->b} holds for any pair of times, so
// the estimator pairs each new keyframe b with an older keyframe a far enough back that the
// master motion a->b is large (a good signal), but not so far that odometry drift dominates.

#include <cstdint>
#include <deque>
#include <optional>

#include "rigcal/base/types.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

struct Keyframe {
  int64_t t_ns = 0;
  Pose master;
  Pose slave;
  int segment = 0;  // the slave's odometry segment
};

// Makes the set (master and slave pose at t_ns) a keyframe when the master has rotated by
// keyframe_min_angle_deg or moved by `min_translation` (master units: MasterTravel's distance
// in keyframe_min_travel_s) since the last keyframe, or keyframe_max_interval_ns has passed;
// keeps the last keyframe_history keyframes. A new slave odometry segment drops the older
// keyframes (pairs never cross a scale segment). Returns whether the set became a keyframe.
bool OfferKeyframe(const RigEstimatorOptions& options, double min_translation, int64_t t_ns,
                   const CameraPose& master, const CameraPose& slave,
                   std::deque<Keyframe>* keyframes);

// The motion from an older keyframe a to the newest one b.
struct KeyframePair {
  RigMotion motion;
  // How many keyframes a->b spans, and the angle invariant |angle_0 - angle_i| (degrees) of the
  // consecutive-keyframe motion ending at b, which holds the drift of one keyframe interval
  // only (the online σ counts the drift that overlapping pairs share, online_uncertainty.h).
  double span_keyframes = 1.0;
  double consecutive_angle_diff_deg = 0.0;
};

// Pairs the newest keyframe b with the latest older a for which the master motion a->b reaches
// pair_target_angle_deg or pair_target_translation_fraction of the extent of the keyframes,
// within pair_max_span_ns. nullopt with fewer than two keyframes or no a within the span.
std::optional<KeyframePair> PairNewestKeyframe(const RigEstimatorOptions& options,
                                               const std::deque<Keyframe>& keyframes);

}  // namespace rigcal::internal
