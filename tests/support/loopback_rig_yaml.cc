// SPDX-License-Identifier: Apache-2.0
#include "support/loopback_rig_yaml.h"

#include <cmath>
#include <sstream>

namespace rigcal::support {

std::string SimulatedLoopbackRigYaml(int width, int height, int frames, int seed) {
  const double f = (width / 2.0) / std::tan(30.0 * M_PI / 180.0);
  std::ostringstream camera;
  camera << "model: pinhole, resolution: [" << width << ", " << height << "], intrinsics: [" << f
         << ", " << f << ", " << (width - 1) / 2.0 << ", " << (height - 1) / 2.0 << "]";
  std::ostringstream yaml;
  yaml << "rig: {name: loopback, master: cam0}\n"
       << "cameras:\n"
       << "  - {name: cam0, " << camera.str() << "}\n"
       << "  - {name: cam1, " << camera.str()
       << ",\n     truth: {q_wxyz: [0.70710678118654752, 0, 0.70710678118654752, 0], "
          "C: [-1, 1, 3]}}\n"
       << "source:\n"
       << "  type: simulated\n"
       << "  frame_rate_hz: " << frames / kLoopbackDriveS << "\n"
       << "  num_frames: " << frames << "\n"
       << "  seed: " << seed << "\n"
       << "  realtime: false\n"
       << "  noise_sigma: 1.5\n"
       << "  scene: {type: room, size: [20, 16, 6], boxes: 10}\n"
       << "  trajectory:\n"
       << "    waypoint_interval_s: 2\n"
       << "    waypoints:\n"
       << "      - {p: [-3.0, 0.0, 3.0], ypr_deg: [0, 0, 0]}\n"
       << "      - {p: [-2.3, 0.8, 3.2], ypr_deg: [20, -10, 8]}\n"
       << "      - {p: [-1.4, 1.5, 3.0], ypr_deg: [38, 5, -6]}\n"
       << "      - {p: [-0.4, 1.2, 2.8], ypr_deg: [15, 15, -15]}\n"
       << "      - {p: [0.5, 0.4, 3.1], ypr_deg: [-10, 0, 5]}\n"
       << "      - {p: [1.2, -0.6, 3.4], ypr_deg: [-35, -15, 12]}\n"
       << "      - {p: [0.8, -1.6, 3.1], ypr_deg: [-20, 8, 18]}\n";
  return yaml.str();
}

}  // namespace rigcal::support
