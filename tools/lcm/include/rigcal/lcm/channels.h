// SPDX-License-Identifier: Apache-2.0
#pragma once
// The LCM channels of rigcal (docs/architecture.md): RIGCAL_EXTRINSICS, RIGCAL_STATUS, and a
// RIGCAL_POSE_<camera> and RIGCAL_IMAGE_<camera> channel per camera.

#include <string>
#include <string_view>

namespace rigcal::lcm {

inline constexpr char kExtrinsicsChannel[] = "RIGCAL_EXTRINSICS";  // rig_extrinsics_t
inline constexpr char kStatusChannel[] = "RIGCAL_STATUS";          // rig_status_t
std::string PoseChannel(std::string_view camera);   // "RIGCAL_POSE_<camera>", camera_pose_t
std::string ImageChannel(std::string_view camera);  // "RIGCAL_IMAGE_<camera>", image_t

}  // namespace rigcal::lcm
