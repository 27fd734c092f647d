#pragma once
// LCM logs of camera poses: a recording written as RIGCAL_POSE_<camera> events (camera_pose_t),
// the input `rigcal calib --log` and lcm-logplayer replay.

#include <string>

#include "rigcal/calib/status.h"
#include "rigcal/calib/types.h"

namespace rigcal::tools {

// Writes every pose of `recording` as a camera_pose_t event on RIGCAL_POSE_<name>, in time
// order (master first at equal stamps), event timestamps = t_ns / 1000 µs. Slave segment ids
// are carried. Atomic (AtomicFile). The error names the path or the invalid pose.
[[nodiscard]] Status WritePoseLog(const std::string& path, const RigRecording& recording);

}  // namespace rigcal::tools
