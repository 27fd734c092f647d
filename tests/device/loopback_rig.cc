// SPDX-License-Identifier: Apache-2.0
#include "loopback_rig.h"

#include <cmath>
#include <regex>
#include <sstream>

namespace rigcal::device_test {

std::string SimulatedLoopbackRigYaml(int width, int height, int frames) {
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
       << "  seed: 3\n"
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

// The same cameras, captured from the loopback devices.
std::string V4l2LoopbackRigYaml(const std::string& simulated) {
  std::string yaml = simulated.substr(0, simulated.find("source:"));
  yaml = std::regex_replace(yaml, std::regex("name: cam0, "), "name: cam0, device: /dev/video20, ");
  yaml = std::regex_replace(
      yaml, std::regex("name: cam1, "),
      "name: cam1, device: /dev/video21, capture: {pixel_formats: [YUYV]},\n     ");
  // Under emulation the writer feeds about one frame a second where the simulation runs at 20:
  // the drive plays about 20 times slower, and the stream-time settings say so. Sets are the
  // writer's frames (both written within milliseconds, frames at least 150 ms apart): a 100 ms
  // tolerance; a nominal 0.5 Hz rate lets a pose wait 6 s for its partner and a VO segment start
  // up to 60 s (the clock-glitch horizon) before its first tracked pose. The rotation sigma's
  // error blocks (10 s of the 20 Hz drive) last 200 s.
  yaml += "sync: {frame_rate_hz: 0.5, tolerance_ms: 100}\n";
  yaml += "estimator: {sigma_block_s: 200}\n";
  yaml += "source: {type: v4l2, pixel_formats: [GREY], buffers: 4}\n";
  return yaml;
}

}  // namespace rigcal::device_test
