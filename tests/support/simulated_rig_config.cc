// SPDX-License-Identifier: Apache-2.0
#include "support/simulated_rig_config.h"

#include <fstream>
#include <sstream>

namespace rigcal::support {
namespace {

// `text` with every occurrence of `from` replaced by `to`.
std::string ReplaceAll(std::string text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size())) {
    text.replace(at, from.size(), to);
  }
  return text;
}

}  // namespace

std::string SimulatedRigConfig(int width, int height, int frames) {
  std::ifstream in(std::string(RIGCAL_SOURCE_DIR) + "/config/sim_thesis_virtual.yaml");
  std::stringstream shipped;
  shipped << in.rdbuf();
  const double f = 0.866 * width;  // 60 degrees horizontal field of view, as shipped
  std::ostringstream intrinsics;
  intrinsics << "intrinsics: [" << f << ", " << f << ", " << width / 2.0 - 0.5 << ", "
             << height / 2.0 - 0.5 << "]";
  std::string config = shipped.str();
  config =
      ReplaceAll(config, "resolution: [752, 480]",
                 "resolution: [" + std::to_string(width) + ", " + std::to_string(height) + "]");
  config = ReplaceAll(config, "intrinsics: [651.2511, 651.2511, 375.5, 239.5]", intrinsics.str());
  return ReplaceAll(config, "num_frames: 468", "num_frames: " + std::to_string(frames));
}

}  // namespace rigcal::support
