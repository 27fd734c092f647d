#include "support/simulated_rig_config.h"

namespace rigcal::support {

std::string SimulatedRigConfig(int width, int height, int frames) {
  const double f = 0.866 * width;  // 60 degrees horizontal field of view
  const std::string camera = "    model: pinhole\n    resolution: [" + std::to_string(width) +
                             ", " + std::to_string(height) + "]\n    intrinsics: [" +
                             std::to_string(f) + ", " + std::to_string(f) + ", " +
                             std::to_string(width / 2.0 - 0.5) + ", " +
                             std::to_string(height / 2.0 - 0.5) + "]\n";
  return "rig: {name: simulated_test_rig, master: cam0}\n"
         "cameras:\n"
         "  - name: cam0\n" +
         camera + "  - name: cam1\n" + camera +
         "    truth: {q_wxyz: [0.70710678118654752, 0, 0.70710678118654752, 0], C: [-1, 1, 3]}\n"
         "source:\n"
         "  type: simulated\n"
         "  frame_rate_hz: 20\n"
         "  num_frames: " +
         std::to_string(frames) +
         "\n"
         "  seed: 1\n"
         "  realtime: true\n"
         "  scene: {type: room, size: [20, 16, 6], boxes: 10}\n"
         "  trajectory:\n"
         "    waypoint_interval_s: 2\n"
         "    waypoints:\n"
         "      - {p: [-3.0, 0.0, 3.0], ypr_deg: [0, 0, 0]}\n"
         "      - {p: [-2.3, 0.8, 3.2], ypr_deg: [20, -10, 8]}\n"
         "      - {p: [-1.4, 1.5, 3.0], ypr_deg: [38, 5, -6]}\n"
         "      - {p: [-0.4, 1.2, 2.8], ypr_deg: [15, 15, -15]}\n"
         "      - {p: [0.5, 0.4, 3.1], ypr_deg: [-10, 0, 5]}\n"
         "      - {p: [1.2, -0.6, 3.4], ypr_deg: [-35, -15, 12]}\n";
}

}  // namespace rigcal::support
