// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/pose_message.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "message_checker.h"
#include "message_codec.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm {
namespace {

using internal::Checker;
using internal::LayoutWalk;

// The fields of camera_pose_t.lcm up to the camera name (it has no arrays of variable length).
void WalkPoseLayout(LayoutWalk* walk) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Fixed("t_ns", 8);
  walk->String("camera");
}

// The rules of camera_pose_t (pose_message.h) but the version.
void CheckPose(const CameraNames& names, camera_pose_t* msg, Checker* check) {
  check->Finite("q", msg->q, 4);
  check->Finite("C", msg->C, 3);
  check->Finite("quality", msg->quality);
  if (msg->has_covariance) check->Finite("covariance", msg->covariance, 36);
  check->Quaternion("q", msg->q);
  check->CameraName("camera", msg->camera, names, 0, "the rig's cameras");
  check->AtLeast<int64_t>("utime", msg->utime, 0);
  check->AtLeast<int64_t>("t_ns", msg->t_ns, 0);
  check->AtLeast<int64_t>("trigger_seq", msg->trigger_seq, -1);
  check->AtLeast<int32_t>("segment", msg->segment, 0);
  check->InRange("quality", msg->quality, 0.0, 1.0);
  if (msg->has_covariance) {
    const double* cov = msg->covariance;
    double max_abs = 0.0;
    for (int i = 0; i < 36; ++i) max_abs = std::max(max_abs, std::abs(cov[i]));
    for (int r = 0; r < 6 && check->ok(); ++r) {
      check->AtLeast("covariance[" + std::to_string(r * 7) + "]", cov[r * 7], 0.0);
      for (int c = r + 1; c < 6; ++c) {
        if (std::abs(cov[r * 6 + c] - cov[c * 6 + r]) > 1e-9 * std::max(1.0, max_abs)) {
          check->Fail(RejectCause::kOutOfRange, "covariance",
                      "not symmetric: element (" + std::to_string(r) + ", " + std::to_string(c) +
                          ") = " + internal::FormatNumber(cov[r * 6 + c]) + ", (" +
                          std::to_string(c) + ", " + std::to_string(r) +
                          ") = " + internal::FormatNumber(cov[c * 6 + r]));
          break;
        }
      }
    }
  }
}

}  // namespace

template <>
struct internal::MessageTraits<camera_pose_t> {
  static constexpr char kTypeName[] = "camera_pose_t";
  static constexpr auto WalkLayout = &WalkPoseLayout;
  static constexpr auto CheckContent = &CheckPose;
};

Expected<camera_pose_t> CameraPoseToLcm(const CameraPose& pose, const CameraNames& names,
                                        int64_t utime, const Matrix6d* covariance) {
  if (pose.camera < 0 || static_cast<size_t>(pose.camera) >= names.size()) {
    return Error{"CameraPoseToLcm: camera index " + std::to_string(pose.camera) +
                 " is not in the name table of " + std::to_string(names.size()) + " cameras"};
  }
  camera_pose_t msg;
  msg.version = camera_pose_t::VERSION;
  msg.utime = utime;
  msg.t_ns = pose.t_ns;
  msg.camera = names[pose.camera];
  msg.trigger_seq = pose.trigger_seq;
  msg.segment = pose.segment;
  const Eigen::Quaterniond& q = pose.pose.q;
  msg.q[0] = q.w();
  msg.q[1] = q.x();
  msg.q[2] = q.y();
  msg.q[3] = q.z();
  for (int i = 0; i < 3; ++i) msg.C[i] = pose.pose.C[i];
  msg.quality = pose.quality;
  msg.has_covariance = covariance != nullptr;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) msg.covariance[r * 6 + c] = covariance ? (*covariance)(r, c) : 0.0;
  }
  if (std::optional<Rejection> rejection = CheckMessage(PoseChannel(msg.camera), names, &msg)) {
    return Error{rejection->message};
  }
  return msg;
}

Expected<PoseMessage> CameraPoseFromLcm(std::string_view channel, const camera_pose_t& msg,
                                        const CameraNames& names) {
  camera_pose_t checked = msg;
  if (std::optional<Rejection> rejection = CheckMessage(channel, names, &checked)) {
    return Error{rejection->message};
  }
  const auto it = std::find(names.begin(), names.end(), checked.camera);
  if (it == names.end()) {  // only reachable with an empty table
    return Error{std::string(channel) + ": camera_pose_t.camera: camera '" + checked.camera +
                 "' is not one of the rig's cameras (" + ToString(RejectCause::kUnknownCamera) +
                 ")"};
  }
  PoseMessage out;
  out.utime = checked.utime;
  out.pose.camera = static_cast<int>(it - names.begin());
  out.pose.t_ns = checked.t_ns;
  out.pose.trigger_seq = checked.trigger_seq;
  out.pose.segment = checked.segment;
  out.pose.pose.q = Eigen::Quaterniond(checked.q[0], checked.q[1], checked.q[2], checked.q[3]);
  out.pose.pose.C = Eigen::Vector3d(checked.C[0], checked.C[1], checked.C[2]);
  out.pose.quality = checked.quality;
  if (checked.has_covariance) {
    Matrix6d cov;
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) cov(r, c) = checked.covariance[r * 6 + c];
    }
    out.covariance = cov;
  }
  return out;
}

Expected<PoseMessage> MessageValidator::DecodeCameraPose(std::string_view channel, const void* data,
                                                         int64_t size) {
  camera_pose_t msg;
  if (std::optional<Rejection> rejection = DecodeUncounted(channel, data, size, &msg)) {
    return Reject(std::move(*rejection));
  }
  const auto it = std::find(names_.begin(), names_.end(), msg.camera);
  if (it == names_.end()) {  // an empty table accepted the name; the index is needed here
    internal::Checker check(channel, "camera_pose_t");
    check.Fail(RejectCause::kUnknownCamera, "camera",
               "camera '" + msg.camera + "' is not one of the rig's cameras");
    return Reject(*check.TakeRejection());
  }
  Expected<PoseMessage> pose = CameraPoseFromLcm(channel, msg, names_);
  if (!pose) return Reject(Rejection{RejectCause::kMalformed, pose.error()});  // not reached
  ++stats_.accepted;
  return pose;
}

template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                               camera_pose_t*);
template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                      camera_pose_t);
template Expected<camera_pose_t> MessageValidator::Decode(std::string_view, const void*, int64_t);

}  // namespace rigcal::lcm
