// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm {

std::string PoseChannel(std::string_view camera) { return "RIGCAL_POSE_" + std::string(camera); }
std::string ImageChannel(std::string_view camera) { return "RIGCAL_IMAGE_" + std::string(camera); }

}  // namespace rigcal::lcm
