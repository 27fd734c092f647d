// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated two-camera rig the loopback tests feed through v4l2loopback
// (scripts/vm/guest-init.sh: /dev/video20 and /dev/video21): its config with the simulated
// source, and the same cameras captured from the loopback devices (GREY and YUYV).

#include <string>

namespace rigcal::device_test {

constexpr double kLoopbackDriveS = 12.0;  // the trajectory: 7 waypoints, 2 s apart

// cam0 (master) and cam1 (slave, 90 degrees about y, C = [-1, 1, 3]), 60-degree pinhole cameras
// of width x height, `frames` frames over the 12-s drive in a room with boxes (seed 3), not
// paced in real time.
std::string SimulatedLoopbackRigYaml(int width, int height, int frames);

// The cameras of `simulated` captured from /dev/video20 (GREY) and /dev/video21 (YUYV), with the
// stream-time settings of a writer feeding about a frame a second under emulation.
std::string V4l2LoopbackRigYaml(const std::string& simulated);

}  // namespace rigcal::device_test
