// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated two-camera rig of the loopback device tests (tests/device/loopback_rig.h) and of
// the VO-fed σ evaluation (cli/vo_fed_sigma_eval): its config with the simulated source.

#include <string>

namespace rigcal::support {

constexpr double kLoopbackDriveS = 12.0;  // the trajectory: 7 waypoints, 2 s apart

// cam0 (master) and cam1 (slave, 90 degrees about y, C = [-1, 1, 3]), 60-degree pinhole cameras
// of width x height, `frames` frames over the 12-s drive in a room with boxes drawn from `seed`,
// not paced in real time.
std::string SimulatedLoopbackRigYaml(int width, int height, int frames, int seed = 3);

}  // namespace rigcal::support
