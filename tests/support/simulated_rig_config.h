#pragma once
// A small simulated rig config for tests that run `rigcal record` / `rigcal run`: two 60-degree
// pinhole cameras (cam1 looks to the master's right, 3.3 m away: the thesis 5.4 mounting), the
// room scene, 6-DoF waypoints, 20 Hz.

#include <string>

namespace rigcal::support {

// The config YAML text: `width` x `height` pixels, `frames` frames per camera, `realtime: true`
// (pass --fast to record or run without pacing).
std::string SimulatedRigConfig(int width, int height, int frames);

}  // namespace rigcal::support
