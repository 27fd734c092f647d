// SPDX-License-Identifier: Apache-2.0
#include "loopback_rig.h"

#include <regex>
#include <sstream>

namespace rigcal::device_test {

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
