// SPDX-License-Identifier: Apache-2.0
#pragma once
// camera_pose_t, one camera's pose on RIGCAL_POSE_<camera>: its checks and its conversion from
// and to CameraPose.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera_pose_t.hpp"
#include "rigcal/lcm/message_validation.h"

namespace rigcal::lcm {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// A CameraPose as carried by camera_pose_t.
struct PoseMessage {
  CameraPose pose;
  // Covariance of (rotation vector, camera centre), rotation error on the left (world frame):
  // R = Exp(dtheta) R_est. Absent when the sender had none.
  std::optional<Matrix6d> covariance;
  int64_t utime = 0;  // publish time, µs
};

// The rules of camera_pose_t (beyond message_validation.h), checked by CheckMessage, EncodeMessage
// and MessageValidator::Decode: finite q, C, quality (and covariance when has_covariance), unit q,
// a known camera, utime and t_ns >= 0, trigger_seq >= -1, segment >= 0, quality in [0, 1], a
// symmetric covariance with a non-negative diagonal.
extern template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                                      camera_pose_t*);
extern template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                             camera_pose_t);
extern template Expected<camera_pose_t> MessageValidator::Decode(std::string_view, const void*,
                                                                 int64_t);

// camera_pose_t of `pose` published at `utime` (µs); the camera name is names[pose.camera].
// `covariance` (nullable): 6x6 covariance of (rotation vector, centre), see PoseMessage.
// Fails when pose.camera is not an index of `names` or the message would not pass CheckMessage
// (the message names the field). The quaternion is normalised.
Expected<camera_pose_t> CameraPoseToLcm(const CameraPose& pose, const CameraNames& names,
                                        int64_t utime, const Matrix6d* covariance = nullptr);

// The CameraPose of a camera_pose_t received on `channel`: checks it (CheckMessage) and maps
// the camera name to its index in `names`; a name not in `names` (or an empty `names`) is
// rejected with kUnknownCamera. Rejections are not counted (MessageValidator counts).
Expected<PoseMessage> CameraPoseFromLcm(std::string_view channel, const camera_pose_t& msg,
                                        const CameraNames& names);

}  // namespace rigcal::lcm
