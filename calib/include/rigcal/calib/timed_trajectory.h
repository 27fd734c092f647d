// SPDX-License-Identifier: Apache-2.0
#pragma once
// The poses of one camera with their time stamps, on the camera's own clock: what a trajectory
// file holds (tools/io trajectory_io.h) and what the clock offset estimation of cameras that run
// free works on (clock_offset.h).

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal {

// Entry k of each vector belongs together.
struct TimedTrajectory {
  std::string name;           // camera name (the file stem for a file: "cam1" for /data/cam1.txt)
  std::vector<int64_t> t_ns;  // strictly increasing, nanoseconds
  std::vector<Pose> poses;    // world_from_camera, centre in the camera's world frame
  std::vector<int> segment;   // scale segment id per pose (0 when the source has none)

  size_t size() const { return t_ns.size(); }
};

}  // namespace rigcal
