// SPDX-License-Identifier: Apache-2.0
#pragma once
// A small version of the shipped thesis 5.4 rig (config/sim_thesis_virtual.yaml) for tests that
// run `rigcal record` / `rigcal run`: two 60-degree pinhole cameras (cam1 looks to the master's
// right, 3.3 m away), the room scene, the shipped 6-DoF waypoints, 20 Hz, paced in real time
// (pass --fast to go without pacing).

#include <string>

namespace rigcal::support {

// The config YAML text with `width` x `height` pixel cameras and `frames` frames per camera.
std::string SimulatedRigConfig(int width, int height, int frames);

}  // namespace rigcal::support
