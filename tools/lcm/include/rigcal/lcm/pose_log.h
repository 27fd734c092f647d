// SPDX-License-Identifier: Apache-2.0
#pragma once
// LCM logs of camera poses: a recording written as RIGCAL_POSE_<camera> events (camera_pose_t),
// the input `rigcal calib --log` and lcm-logplayer replay.

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/lcm/message_validation.h"

namespace rigcal::lcm {

// Writes every pose of `recording` as a camera_pose_t event on RIGCAL_POSE_<name>, in time
// order (master first at equal stamps), event timestamps = t_ns / 1000 µs. Slave segment ids
// are carried. Atomic (AtomicFile). The error names the path or the invalid pose.
[[nodiscard]] Status WritePoseLog(const std::string& path, const RigRecording& recording);

// Writes `poses` (any order; pose.camera indexes `names`, names[0] the master) as camera_pose_t
// events on RIGCAL_POSE_<name>, sorted by time (lower camera index first at equal stamps), event
// timestamps and utime = t_ns / 1000 µs. Unlike WritePoseLog the cameras need not share stamps
// (per-camera trajectories). Atomic; replaces `path`. The error names the path or the pose.
[[nodiscard]] Status WritePoseEvents(const std::string& path, const CameraNames& names,
                                     std::vector<CameraPose> poses);

}  // namespace rigcal::lcm
