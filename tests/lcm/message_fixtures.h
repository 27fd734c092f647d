// SPDX-License-Identifier: Apache-2.0
#pragma once
// Fixtures of the tests in tests/lcm/: a valid message of every rigcal LCM type with every field
// set, LCM's unchecked encoding (how a faulty sender makes its bytes), byte offsets to corrupt a
// buffer, and expectations on round trips and rejections.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::lcm::lcm_test {

using ::testing::HasSubstr;

inline const CameraNames kNames = {"front", "left", "back"};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- Valid messages of every type, every field set ----

inline camera_pose_t MakePoseMsg(const std::string& camera = "left") {
  camera_pose_t m{};
  m.version = camera_pose_t::VERSION;
  m.utime = 1'700'000'123;
  m.t_ns = 1'700'000'000'123'456;
  m.camera = camera;
  m.trigger_seq = 4711;
  m.segment = 2;
  const Eigen::Quaterniond q = AxisAngle(Eigen::Vector3d(1, 2, 3).normalized(), 0.7);
  m.q[0] = q.w();
  m.q[1] = q.x();
  m.q[2] = q.y();
  m.q[3] = q.z();
  m.C[0] = 1.5;
  m.C[1] = -2.25;
  m.C[2] = 0.125;
  m.quality = 0.8;
  m.has_covariance = true;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) m.covariance[r * 6 + c] = (r == c) ? 0.01 * (r + 1) : 1e-4;
  }
  return m;
}

inline slave_extrinsics_t MakeSlaveMsg(const std::string& name, double angle_deg) {
  slave_extrinsics_t s{};
  s.name = name;
  const Eigen::Quaterniond q = AxisAngle(Eigen::Vector3d::UnitY(), angle_deg * kRadPerDeg);
  s.q[0] = q.w();
  s.q[1] = q.x();
  s.q[2] = q.y();
  s.q[3] = q.z();
  s.C[0] = -0.84;
  s.C[1] = 0.05;
  s.C[2] = -0.61;
  s.scale = 0.505;
  s.segment = 1;
  s.rot_std_deg = 0.02;
  s.pos_std[0] = 0.001;
  s.pos_std[1] = 0.002;
  s.pos_std[2] = 0.003;
  s.scale_std = 0.004;
  s.motions_used = 190;
  s.motions_rejected = 10;
  s.rotation_eigen_gap = 12.5;
  s.position_min_eigenvalue = 0.3;
  s.axis_spread_deg = 35.0;
  s.state = slave_extrinsics_t::STATE_CONVERGED;
  s.flags = 0;
  s.message = "converged: after 7 iterations";
  return s;
}

inline rig_extrinsics_t MakeExtrinsicsMsg() {
  rig_extrinsics_t m{};
  m.version = rig_extrinsics_t::VERSION;
  m.utime = 1'700'000'456;
  m.t_ns = 1'700'000'000'000'000;
  m.master = "front";
  m.distance_unit = rig_extrinsics_t::UNIT_MASTER_ODOMETRY;
  m.slaves = {MakeSlaveMsg("left", -89.5), MakeSlaveMsg("back", 179.0)};
  m.slaves[1].state = slave_extrinsics_t::STATE_INITIALISING;
  m.slaves[1].flags = kWireFlagPlanar;
  m.slaves[1].planar_axis[2] = 1.0;
  m.num_slaves = 2;
  return m;
}

inline camera_status_t MakeCameraStatus(const std::string& name, int k) {
  camera_status_t c{};
  c.name = name;
  c.fps = 29.5 + k;
  c.frames_received = 1000 + k;
  c.dropped_late = 1 + k;
  c.dropped_duplicate = 2 + k;
  c.dropped_out_of_order = 3 + k;
  c.dropped_overflow = 4 + k;
  c.dropped_never_matched = 5 + k;
  c.dropped_invalid = 6 + k;
  c.vo_state = camera_status_t::VO_TRACKING;
  c.last_pose_age_ms = 33 + k;
  c.vo_segment = 2 + k;
  c.relocalisations = 7 + k;
  c.time_offset_std_s = -1.0;  // synchronised stamps: no clock offset
  c.clock_drift_std_ppm = -1.0;
  return c;
}

inline rig_status_t MakeStatusMsg() {
  rig_status_t m{};
  m.version = rig_status_t::VERSION;
  m.utime = 1'700'000'789;
  m.cameras = {MakeCameraStatus("front", 0), MakeCameraStatus("left", 1),
               MakeCameraStatus("back", 2)};
  m.cameras[2].vo_state = camera_status_t::VO_LOST;
  m.num_cameras = 3;
  m.sync_sets_emitted = 987;
  m.sync_fill = 12;
  m.sync_capacity = 64;
  m.estimator_state = rig_status_t::ESTIMATOR_DEGRADED;
  m.estimator_message = "back: insufficient motion";
  m.cpu_percent = 143.5;
  m.rss_bytes = 123'456'789;
  return m;
}

// A 4x3 GREY image with 1 byte of row padding.
inline image_t MakeImageMsg() {
  image_t m{};
  m.version = image_t::VERSION;
  m.utime = 1'700'000'999;
  m.t_ns = 1'700'000'000'999'000;
  m.camera = "back";
  m.trigger_seq = 4712;
  m.width = 4;
  m.height = 3;
  m.stride = 5;
  m.pixel_format = "GREY";
  m.encoding = image_t::ENCODING_RAW;
  for (int i = 0; i < 15; ++i) m.data.push_back(static_cast<uint8_t>(17 * i));
  m.size = 15;
  return m;
}

// LCM's encoding without any check: how a faulty or hostile sender produces its bytes.
template <typename Message>
std::vector<uint8_t> RawEncode(const Message& msg) {
  std::vector<uint8_t> buffer(msg.getEncodedSize());
  EXPECT_EQ(msg.encode(buffer.data(), 0, static_cast<int>(buffer.size())),
            static_cast<int>(buffer.size()));
  return buffer;
}

// EncodeMessage with kNames, expected to succeed.
template <typename Message>
std::vector<uint8_t> Encode(std::string_view channel, const Message& msg) {
  Expected<std::vector<uint8_t>> encoded = EncodeMessage(channel, kNames, msg);
  EXPECT_TRUE(encoded.ok()) << encoded.error();
  return encoded.ok() ? *encoded : std::vector<uint8_t>();
}

// Overwrites / reads the big-endian int32 at `offset` of an encoded buffer.
inline void PutInt32(std::vector<uint8_t>* buffer, size_t offset, int32_t value) {
  ASSERT_LE(offset + 4, buffer->size());
  const auto v = static_cast<uint32_t>(value);
  for (int i = 0; i < 4; ++i) (*buffer)[offset + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}
inline int32_t GetInt32(const std::vector<uint8_t>& buffer, size_t offset) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | buffer[offset + i];
  return static_cast<int32_t>(v);
}

// Byte offsets of fields in the wire format (8-byte fingerprint first).
inline constexpr size_t kPoseCameraLength = 8 + 2 + 8 + 8;  // camera_pose_t.camera's length
inline size_t ExtrinsicsNumSlavesOffset(const rig_extrinsics_t& m) {
  return 8 + 2 + 8 + 8 + 4 + m.master.size() + 1 + 1;
}
inline size_t ImageSizeOffset(const image_t& m) {
  return 8 + 2 + 8 + 8 + 4 + m.camera.size() + 1 + 8 + 4 + 4 + 4 + 4 + m.pixel_format.size() + 1 +
         1;
}

// Decodes `buffer` as Message on `channel` and expects exactly one rejection, of `cause`, whose
// message names the channel, every string of `parts` and the cause.
template <typename Message>
void ExpectRejected(MessageValidator* validator, const std::string& channel,
                    const std::vector<uint8_t>& buffer, RejectCause cause,
                    const std::vector<std::string>& parts) {
  const DecodeStats before = validator->stats();
  Expected<Message> decoded = validator->Decode<Message>(channel, buffer.data(), buffer.size());
  ASSERT_FALSE(decoded.ok()) << "accepted, expected " << ToString(cause);
  const DecodeStats& after = validator->stats();
  EXPECT_EQ(after.Rejected(cause), before.Rejected(cause) + 1)
      << "cause " << ToString(cause) << ", got: " << decoded.error();
  EXPECT_EQ(after.TotalRejected(), before.TotalRejected() + 1);
  EXPECT_EQ(after.accepted, before.accepted);
  ASSERT_TRUE(after.last_rejection.has_value());
  EXPECT_EQ(after.last_rejection->cause, cause);
  EXPECT_EQ(after.last_rejection->message, decoded.error());
  EXPECT_THAT(decoded.error(), HasSubstr(channel + ": "));
  EXPECT_THAT(decoded.error(), HasSubstr(std::string("(") + ToString(cause) + ")"));
  for (const std::string& part : parts) EXPECT_THAT(decoded.error(), HasSubstr(part));
}

// Encodes `msg` (checked) on `channel`, decodes it with a fresh validator and expects it accepted
// with every field intact; returns the decoded message.
template <typename Message>
Message ExpectRoundTrip(const std::string& channel, const Message& msg) {
  const std::vector<uint8_t> buffer = Encode(channel, msg);
  MessageValidator validator(kNames);
  Expected<Message> decoded = validator.Decode<Message>(channel, buffer.data(), buffer.size());
  EXPECT_TRUE(decoded.ok()) << decoded.error();
  EXPECT_EQ(validator.stats().accepted, 1);
  EXPECT_EQ(validator.stats().TotalRejected(), 0);
  if (!decoded.ok()) return msg;
  EXPECT_EQ(RawEncode(*decoded), buffer);  // every field survived
  return *decoded;
}

// A converged general-motion calibration of slave `name`.
inline SlaveCalibration MakeSlave(const std::string& name) {
  SlaveCalibration s;
  s.name = name;
  s.estimate.q = AxisAngle(Eigen::Vector3d::UnitY(), -1.5);
  s.estimate.C = Eigen::Vector3d(-0.8, 0.05, -0.6);
  s.estimate.scale = 0.5;
  s.scales = {SegmentScale{0, 0.5, 0.001}};
  s.rot_std_deg = 0.03;
  s.pos_std = Eigen::Vector3d(0.01, 0.02, 0.03);
  s.motions.total = 100;
  s.motions.used = 90;
  s.motions.small_rotation = 6;
  s.motions.residual_outlier = 4;
  s.motion_model = MotionModel::kGeneral;
  s.observability.rotation_eigenvalues = Eigen::Vector4d(0.001, 4.0, 5.0, 6.0);
  s.observability.position_min_eigenvalue = 0.25;
  s.observability.axis_spread_deg = 40.0;
  s.termination = Termination::kSolved;
  s.state = SlaveState::kConverged;
  s.message = "after 5 iterations";
  return s;
}

}  // namespace rigcal::lcm::lcm_test
