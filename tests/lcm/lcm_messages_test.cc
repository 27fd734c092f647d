// The rigcal LCM messages: encode/decode round trips of every type, conversion from and to the
// calib types, every rejection cause of the validator, in-process publish/subscribe (memq://)
// and LCM log files. Never UDP multicast (DESIGN.md "LCM").
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <string>
#include <vector>

#include "rigcal/calib/quaternion.h"

namespace rigcal::tools {
namespace {

using ::testing::HasSubstr;

const CameraNames kNames = {"front", "left", "back"};
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- Valid messages of every type, every field set ----

camera_pose_t MakePoseMsg(const std::string& camera = "left") {
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

slave_extrinsics_t MakeSlaveMsg(const std::string& name, double angle_deg) {
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
  s.flags = kFlagConverged;
  s.message = "converged: after 7 iterations";
  return s;
}

rig_extrinsics_t MakeExtrinsicsMsg() {
  rig_extrinsics_t m{};
  m.version = rig_extrinsics_t::VERSION;
  m.utime = 1'700'000'456;
  m.t_ns = 1'700'000'000'000'000;
  m.master = "front";
  m.distance_unit = rig_extrinsics_t::UNIT_MASTER_ODOMETRY;
  m.slaves = {MakeSlaveMsg("left", -89.5), MakeSlaveMsg("back", 179.0)};
  m.slaves[1].flags = kFlagInitialising | kFlagPlanar;
  m.slaves[1].planar_axis[2] = 1.0;
  m.num_slaves = 2;
  return m;
}

camera_status_t MakeCameraStatus(const std::string& name, int k) {
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
  return c;
}

rig_status_t MakeStatusMsg() {
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
image_t MakeImageMsg() {
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

template <typename Message>
std::vector<uint8_t> Encode(std::string_view channel, const Message& msg) {
  Expected<std::vector<uint8_t>> encoded = EncodeMessage(channel, kNames, msg);
  EXPECT_TRUE(encoded.ok()) << encoded.error();
  return encoded.ok() ? *encoded : std::vector<uint8_t>();
}

void PutInt32(std::vector<uint8_t>* buffer, size_t offset, int32_t value) {
  ASSERT_LE(offset + 4, buffer->size());
  const auto v = static_cast<uint32_t>(value);
  for (int i = 0; i < 4; ++i) (*buffer)[offset + i] = static_cast<uint8_t>(v >> (24 - 8 * i));
}
int32_t GetInt32(const std::vector<uint8_t>& buffer, size_t offset) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v = (v << 8) | buffer[offset + i];
  return static_cast<int32_t>(v);
}

// Byte offsets of fields in the wire format (8-byte fingerprint first).
constexpr size_t kPoseCameraLength = 8 + 2 + 8 + 8;  // camera_pose_t.camera's length
size_t ExtrinsicsNumSlavesOffset(const rig_extrinsics_t& m) {
  return 8 + 2 + 8 + 8 + 4 + m.master.size() + 1 + 1;
}
size_t ImageSizeOffset(const image_t& m) {
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

// ---- Round trips ----

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

TEST(LcmMessages, ChannelNames) {
  EXPECT_EQ(PoseChannel("left"), "RIGCAL_POSE_left");
  EXPECT_EQ(ImageChannel("back"), "RIGCAL_IMAGE_back");
  EXPECT_STREQ(kExtrinsicsChannel, "RIGCAL_EXTRINSICS");
  EXPECT_STREQ(kStatusChannel, "RIGCAL_STATUS");
}

TEST(LcmMessages, CameraPoseRoundTrip) {
  const camera_pose_t msg = MakePoseMsg();
  const camera_pose_t back = ExpectRoundTrip(PoseChannel("left"), msg);
  EXPECT_EQ(back.camera, "left");
  EXPECT_EQ(back.t_ns, 1'700'000'000'123'456);
  EXPECT_EQ(back.trigger_seq, 4711);
  EXPECT_EQ(back.segment, 2);
  EXPECT_EQ(back.C[1], -2.25);
  EXPECT_EQ(back.covariance[7], 0.02);
  EXPECT_TRUE(back.has_covariance);
}

TEST(LcmMessages, RigExtrinsicsRoundTrip) {
  const rig_extrinsics_t back = ExpectRoundTrip(kExtrinsicsChannel, MakeExtrinsicsMsg());
  ASSERT_EQ(back.num_slaves, 2);
  ASSERT_EQ(back.slaves.size(), 2u);
  EXPECT_EQ(back.master, "front");
  EXPECT_EQ(back.slaves[0].name, "left");
  EXPECT_EQ(back.slaves[0].motions_used, 190);
  EXPECT_EQ(back.slaves[0].message, "converged: after 7 iterations");
  EXPECT_EQ(back.slaves[1].name, "back");
  EXPECT_EQ(back.slaves[1].flags, kFlagInitialising | kFlagPlanar);
  EXPECT_EQ(back.slaves[1].planar_axis[2], 1.0);
}

TEST(LcmMessages, RigStatusRoundTrip) {
  const rig_status_t back = ExpectRoundTrip(kStatusChannel, MakeStatusMsg());
  ASSERT_EQ(back.cameras.size(), 3u);
  EXPECT_EQ(back.cameras[1].name, "left");
  EXPECT_EQ(back.cameras[1].dropped_never_matched, 6);
  EXPECT_EQ(back.cameras[2].vo_state, camera_status_t::VO_LOST);
  EXPECT_EQ(back.estimator_state, rig_status_t::ESTIMATOR_DEGRADED);
  EXPECT_EQ(back.estimator_message, "back: insufficient motion");
  EXPECT_EQ(back.rss_bytes, 123'456'789);
}

TEST(LcmMessages, ImageRoundTrip) {
  const image_t back = ExpectRoundTrip(ImageChannel("back"), MakeImageMsg());
  EXPECT_EQ(back.pixel_format, "GREY");
  EXPECT_EQ(back.size, 15);
  ASSERT_EQ(back.data.size(), 15u);
  EXPECT_EQ(back.data[14], 17 * 14);

  image_t jpeg = MakeImageMsg();
  jpeg.encoding = image_t::ENCODING_JPEG;
  jpeg.pixel_format = "MJPG";
  jpeg.stride = 0;
  jpeg.data = {0xff, 0xd8, 0xff, 0xd9};
  jpeg.size = 4;
  EXPECT_EQ(ExpectRoundTrip(ImageChannel("back"), jpeg).data[1], 0xd8);
}

TEST(LcmMessages, EmptyArraysRoundTrip) {
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves.clear();
  extrinsics.num_slaves = 0;
  EXPECT_TRUE(ExpectRoundTrip(kExtrinsicsChannel, extrinsics).slaves.empty());
  rig_status_t status = MakeStatusMsg();
  status.cameras.clear();
  status.num_cameras = 0;
  EXPECT_TRUE(ExpectRoundTrip(kStatusChannel, status).cameras.empty());
}

TEST(LcmMessages, NearUnitQuaternionIsNormalised) {
  camera_pose_t msg = MakePoseMsg();
  for (double& v : msg.q) v *= 1.0 + 5e-7;  // within kUnitTolerance
  const std::vector<uint8_t> buffer = RawEncode(msg);
  MessageValidator validator(kNames);
  Expected<camera_pose_t> decoded =
      validator.Decode<camera_pose_t>(PoseChannel("left"), buffer.data(), buffer.size());
  ASSERT_TRUE(decoded.ok()) << decoded.error();
  const double norm = std::sqrt(decoded->q[0] * decoded->q[0] + decoded->q[1] * decoded->q[1] +
                                decoded->q[2] * decoded->q[2] + decoded->q[3] * decoded->q[3]);
  EXPECT_NEAR(norm, 1.0, 1e-15);
  EXPECT_NEAR(decoded->q[1], MakePoseMsg().q[1], 1e-15);
}

// ---- Conversion from and to the calib types ----

TEST(LcmMessages, CameraPoseConversionRoundTrip) {
  CameraPose pose;
  pose.camera = 2;
  pose.t_ns = 5'000'000'123;
  pose.trigger_seq = 99;
  pose.segment = 4;
  pose.pose.q = AxisAngle(Eigen::Vector3d(0.2, -1, 0.4).normalized(), 1.2);
  pose.pose.C = Eigen::Vector3d(3, -4, 5);
  pose.quality = 0.6;
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Random();
  const Matrix6d covariance = a * a.transpose() * 1e-3;

  Expected<camera_pose_t> msg = CameraPoseToLcm(pose, kNames, 777, &covariance);
  ASSERT_TRUE(msg.ok()) << msg.error();
  EXPECT_EQ(msg->camera, "back");
  EXPECT_EQ(msg->version, camera_pose_t::VERSION);
  EXPECT_EQ(msg->covariance[1], covariance(0, 1));  // row-major
  EXPECT_EQ(msg->covariance[6], covariance(1, 0));

  const std::vector<uint8_t> buffer = Encode(PoseChannel("back"), *msg);
  MessageValidator validator(kNames);
  Expected<PoseMessage> back =
      validator.DecodeCameraPose(PoseChannel("back"), buffer.data(), buffer.size());
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(validator.stats().accepted, 1);
  EXPECT_EQ(back->utime, 777);
  EXPECT_EQ(back->pose.camera, 2);
  EXPECT_EQ(back->pose.t_ns, pose.t_ns);
  EXPECT_EQ(back->pose.trigger_seq, 99);
  EXPECT_EQ(back->pose.segment, 4);
  EXPECT_EQ(back->pose.quality, 0.6);
  EXPECT_TRUE(back->pose.pose.q.coeffs().isApprox(pose.pose.q.coeffs(), 1e-15));
  EXPECT_EQ(back->pose.pose.C, pose.pose.C);
  ASSERT_TRUE(back->covariance.has_value());
  EXPECT_EQ(*back->covariance, covariance);

  Expected<camera_pose_t> plain = CameraPoseToLcm(pose, kNames, 778);
  ASSERT_TRUE(plain.ok()) << plain.error();
  EXPECT_FALSE(plain->has_covariance);
  Expected<PoseMessage> plain_back = CameraPoseFromLcm(PoseChannel("back"), *plain, kNames);
  ASSERT_TRUE(plain_back.ok()) << plain_back.error();
  EXPECT_FALSE(plain_back->covariance.has_value());
}

TEST(LcmMessages, CameraPoseConversionRejectsBadInput) {
  CameraPose pose;
  pose.camera = 3;  // kNames has 3 cameras
  Expected<camera_pose_t> msg = CameraPoseToLcm(pose, kNames, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("camera index 3"));

  pose.camera = 1;
  pose.quality = kNaN;
  msg = CameraPoseToLcm(pose, kNames, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("RIGCAL_POSE_left: camera_pose_t.quality: not finite"));

  // A name the table does not have; an empty table cannot give an index either.
  Expected<PoseMessage> from = CameraPoseFromLcm("X", MakePoseMsg("roof"), kNames);
  ASSERT_FALSE(from.ok());
  EXPECT_THAT(from.error(), HasSubstr("camera 'roof'"));
  from = CameraPoseFromLcm("X", MakePoseMsg("left"), {});
  ASSERT_FALSE(from.ok());
  EXPECT_THAT(from.error(), HasSubstr("(unknown_camera)"));
}

SlaveCalibration MakeSlave(const std::string& name) {
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
  s.termination = Termination::kConverged;
  s.message = "after 5 iterations";
  return s;
}

TEST(LcmMessages, RigCalibrationToLcmSetsFlagsAndFields) {
  RigCalibration result;
  result.master = "front";
  SlaveCalibration general = MakeSlave("left");
  general.scales = {SegmentScale{0, 0.5, 0.001}, SegmentScale{3, 0.45, 0.002},
                    SegmentScale{1, 0.55, 0.003}};  // current = the largest segment id
  SlaveCalibration translational = MakeSlave("back");
  translational.motion_model = MotionModel::kTranslational;
  translational.position_observable = false;
  SlaveCalibration planar = MakeSlave("right");
  planar.termination = Termination::kDegenerate;
  planar.message = "all rotations about one axis";
  planar.observability.planar = true;
  planar.observability.planar_axis = Eigen::Vector3d(0, -2, 0);
  SlaveCalibration waiting = MakeSlave("up");
  waiting.termination = Termination::kInsufficientMotion;
  waiting.estimate.q = Eigen::Quaterniond(kNaN, kNaN, kNaN, kNaN);
  waiting.estimate.C = Eigen::Vector3d::Constant(kNaN);
  waiting.scales.clear();
  waiting.estimate.scale = kNaN;
  waiting.rot_std_deg = kInf;
  result.slaves = {general, translational, planar, waiting};

  EXPECT_EQ(SlaveFlags(general), kFlagConverged);
  EXPECT_EQ(SlaveFlags(translational), kFlagConverged | kFlagTranslationalOnly);
  EXPECT_EQ(SlaveFlags(planar), kFlagInitialising | kFlagPlanar);
  EXPECT_EQ(SlaveFlags(waiting), kFlagInitialising);
  SlaveCalibration no_convergence = general;
  no_convergence.termination = Termination::kNoConvergence;  // usable: linear estimate kept
  EXPECT_EQ(SlaveFlags(no_convergence), kFlagConverged);

  Expected<rig_extrinsics_t> msg = RigCalibrationToLcm(result, 1234, 5678);
  ASSERT_TRUE(msg.ok()) << msg.error();
  EXPECT_EQ(msg->version, rig_extrinsics_t::VERSION);
  EXPECT_EQ(msg->utime, 1234);
  EXPECT_EQ(msg->t_ns, 5678);
  EXPECT_EQ(msg->master, "front");
  EXPECT_EQ(msg->distance_unit, rig_extrinsics_t::UNIT_MASTER_ODOMETRY);
  ASSERT_EQ(msg->num_slaves, 4);
  ASSERT_EQ(msg->slaves.size(), 4u);

  const slave_extrinsics_t& left = msg->slaves[0];
  EXPECT_EQ(left.name, "left");
  EXPECT_EQ(left.flags, kFlagConverged);
  EXPECT_NEAR(left.q[0], general.estimate.q.w(), 1e-15);
  EXPECT_NEAR(left.q[2], general.estimate.q.y(), 1e-15);
  EXPECT_EQ(left.C[0], -0.8);
  EXPECT_EQ(left.scale, 0.45);
  EXPECT_EQ(left.segment, 3);
  EXPECT_EQ(left.scale_std, 0.002);
  EXPECT_EQ(left.rot_std_deg, 0.03);
  EXPECT_EQ(left.pos_std[2], 0.03);
  EXPECT_EQ(left.motions_used, 90);
  EXPECT_EQ(left.motions_rejected, 10);
  EXPECT_DOUBLE_EQ(left.rotation_eigen_gap, 3.999);
  EXPECT_EQ(left.position_min_eigenvalue, 0.25);
  EXPECT_EQ(left.axis_spread_deg, 40.0);
  EXPECT_EQ(left.planar_axis[1], 0.0);
  EXPECT_EQ(left.message, "converged: after 5 iterations");

  EXPECT_EQ(msg->slaves[1].flags, kFlagConverged | kFlagTranslationalOnly);

  const slave_extrinsics_t& right = msg->slaves[2];
  EXPECT_EQ(right.flags, kFlagInitialising | kFlagPlanar);
  EXPECT_EQ(right.planar_axis[0], 0.0);
  EXPECT_EQ(right.planar_axis[1], -1.0);  // normalised
  EXPECT_EQ(right.planar_axis[2], 0.0);
  EXPECT_EQ(right.message, "degenerate: all rotations about one axis");

  const slave_extrinsics_t& up = msg->slaves[3];  // placeholders instead of NaN
  EXPECT_EQ(up.flags, kFlagInitialising);
  EXPECT_EQ(up.q[0], 1.0);
  EXPECT_EQ(up.q[1], 0.0);
  EXPECT_EQ(up.C[0], 0.0);
  EXPECT_EQ(up.scale, 1.0);
  EXPECT_EQ(up.segment, 0);
  EXPECT_EQ(up.rot_std_deg, 0.0);
  EXPECT_EQ(up.message, "insufficient_motion: after 5 iterations");

  // Survives the wire with the rig's name table.
  const CameraNames names = {"front", "left", "back", "right", "up"};
  Expected<std::vector<uint8_t>> buffer = EncodeMessage(kExtrinsicsChannel, names, *msg);
  ASSERT_TRUE(buffer.ok()) << buffer.error();
  MessageValidator validator(names);
  Expected<rig_extrinsics_t> decoded =
      validator.Decode<rig_extrinsics_t>(kExtrinsicsChannel, buffer->data(), buffer->size());
  ASSERT_TRUE(decoded.ok()) << decoded.error();
  EXPECT_EQ(RawEncode(*decoded), *buffer);
}

// The offset along the axis of planar motion: unknown (-1), from the nominal mounting (flag,
// with its σ or 0 when held exactly), or estimated with its σ in nearly planar general motion.
TEST(LcmMessages, AxisOffsetOfPlanarAndNearlyPlanarEstimates) {
  SlaveCalibration unknown = MakeSlave("left");
  unknown.motion_model = MotionModel::kPlanar;
  unknown.observability.planar = true;
  unknown.observability.planar_axis = Eigen::Vector3d(0, 1, 0);
  unknown.unobservable = {Eigen::Vector3d(0, 1, 0)};
  SlaveCalibration from_prior = unknown;
  from_prior.name = "back";
  from_prior.unobservable_from_prior = true;
  from_prior.axis_offset_std = 0.03;
  SlaveCalibration held = from_prior;
  held.name = "right";
  held.axis_offset_std = kNaN;
  SlaveCalibration nearly = MakeSlave("up");
  nearly.observability.planar_axis = Eigen::Vector3d(0, 1, 0);
  nearly.axis_offset_std = 0.06;
  RigCalibration result;
  result.master = "front";
  result.slaves = {unknown, from_prior, held, nearly};
  Expected<rig_extrinsics_t> msg = RigCalibrationToLcm(result, 1, 2);
  ASSERT_TRUE(msg.ok()) << msg.error();
  EXPECT_EQ(msg->slaves[0].flags, kFlagConverged | kFlagPlanar);
  EXPECT_EQ(msg->slaves[0].axis_offset_std, -1.0);
  EXPECT_EQ(msg->slaves[1].flags, kFlagConverged | kFlagPlanar | kFlagAxisFromPrior);
  EXPECT_EQ(msg->slaves[1].axis_offset_std, 0.03);
  EXPECT_EQ(msg->slaves[2].axis_offset_std, 0.0);
  EXPECT_EQ(msg->slaves[3].flags, kFlagConverged);
  EXPECT_EQ(msg->slaves[3].axis_offset_std, 0.06);
  EXPECT_EQ(msg->slaves[3].planar_axis[1], 1.0);  // the mean axis, known
  const CameraNames names = {"front", "left", "back", "right", "up"};
  Expected<std::vector<uint8_t>> buffer = EncodeMessage(kExtrinsicsChannel, names, *msg);
  ASSERT_TRUE(buffer.ok()) << buffer.error();
  MessageValidator validator(names);
  EXPECT_TRUE(
      validator.Decode<rig_extrinsics_t>(kExtrinsicsChannel, buffer->data(), buffer->size()).ok());

  // A σ below -1 or between -1 and 0, or the prior flag without the planar one, is refused.
  rig_extrinsics_t bad = *msg;
  bad.slaves[3].axis_offset_std = -0.5;
  Expected<std::vector<uint8_t>> bad_bytes = EncodeMessage(kExtrinsicsChannel, names, bad);
  EXPECT_FALSE(bad_bytes.ok());
  bad = *msg;
  bad.slaves[3].flags |= kFlagAxisFromPrior;
  EXPECT_FALSE(EncodeMessage(kExtrinsicsChannel, names, bad).ok());
}

TEST(LcmMessages, RigCalibrationToLcmRejectsBrokenResults) {
  RigCalibration result;
  result.master = "front";
  result.slaves = {MakeSlave("left")};
  result.slaves[0].estimate.C.y() = kNaN;  // usable but not finite: a bug upstream
  Expected<rig_extrinsics_t> msg = RigCalibrationToLcm(result, 1, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("slave 'left'"));
  EXPECT_THAT(msg.error(), HasSubstr("not finite"));

  result.slaves = {MakeSlave("left")};
  result.slaves[0].observability.planar = true;  // no axis
  msg = RigCalibrationToLcm(result, 1, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("planar_axis"));

  result.slaves = {MakeSlave("left")};
  result.slaves[0].scales[0].scale = -0.5;
  msg = RigCalibrationToLcm(result, 1, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("slave_extrinsics_t.scale"));

  result.slaves = {MakeSlave("left"), MakeSlave("left")};
  msg = RigCalibrationToLcm(result, 1, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("rig_extrinsics_t.slaves[1].name: camera 'left' appears"));

  result.slaves = {MakeSlave("left")};
  msg = RigCalibrationToLcm(result, -1, 0);
  ASSERT_FALSE(msg.ok());
  EXPECT_THAT(msg.error(), HasSubstr("rig_extrinsics_t.utime"));
}

// ---- Every rejection cause ----

TEST(LcmValidation, WrongType) {
  MessageValidator validator(kNames);
  ExpectRejected<rig_extrinsics_t>(&validator, kExtrinsicsChannel, Encode("X", MakePoseMsg()),
                                   RejectCause::kWrongType,
                                   {"rig_extrinsics_t.fingerprint", "does not hold"});
  ExpectRejected<camera_pose_t>(&validator, PoseChannel("back"), Encode("X", MakeImageMsg()),
                                RejectCause::kWrongType, {"camera_pose_t.fingerprint"});
}

TEST(LcmValidation, WrongVersion) {
  MessageValidator validator(kNames);
  camera_pose_t pose = MakePoseMsg();
  pose.version = camera_pose_t::VERSION + 1;
  ExpectRejected<camera_pose_t>(&validator, "RIGCAL_POSE_left", RawEncode(pose),
                                RejectCause::kWrongVersion,
                                {"camera_pose_t.version", "schema version 2"});
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.version = 0;
  ExpectRejected<rig_extrinsics_t>(&validator, kExtrinsicsChannel, RawEncode(extrinsics),
                                   RejectCause::kWrongVersion, {"rig_extrinsics_t.version"});
  rig_status_t status = MakeStatusMsg();
  status.version = -1;
  ExpectRejected<rig_status_t>(&validator, kStatusChannel, RawEncode(status),
                               RejectCause::kWrongVersion, {"rig_status_t.version"});
  image_t image = MakeImageMsg();
  image.version = 7;
  ExpectRejected<image_t>(&validator, "RIGCAL_IMAGE_back", RawEncode(image),
                          RejectCause::kWrongVersion, {"image_t.version"});
  // EncodeMessage refuses to produce it.
  Expected<std::vector<uint8_t>> encoded = EncodeMessage("RIGCAL_POSE_left", kNames, pose);
  ASSERT_FALSE(encoded.ok());
  EXPECT_THAT(encoded.error(), HasSubstr("(wrong_version)"));
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kWrongVersion), 4);
}

TEST(LcmValidation, Truncated) {
  MessageValidator validator(kNames);
  const auto chop = [](std::vector<uint8_t> buffer, size_t bytes) {
    buffer.resize(buffer.size() - bytes);
    return buffer;
  };
  ExpectRejected<camera_pose_t>(&validator, "P", chop(Encode("P", MakePoseMsg()), 1),
                                RejectCause::kTruncated, {"camera_pose_t.buffer"});
  ExpectRejected<rig_extrinsics_t>(&validator, "E", chop(Encode("E", MakeExtrinsicsMsg()), 1),
                                   RejectCause::kTruncated, {"rig_extrinsics_t."});
  ExpectRejected<rig_status_t>(&validator, "S", chop(Encode("S", MakeStatusMsg()), 1),
                               RejectCause::kTruncated, {"rig_status_t."});
  ExpectRejected<image_t>(&validator, "I", chop(Encode("I", MakeImageMsg()), 1),
                          RejectCause::kTruncated, {"image_t.size", "15 elements"});
  // Shorter than the fingerprint, than the version, ending inside a string.
  ExpectRejected<camera_pose_t>(&validator, "P", std::vector<uint8_t>(5, 0),
                                RejectCause::kTruncated, {"camera_pose_t.fingerprint"});
  std::vector<uint8_t> pose = Encode("P", MakePoseMsg());
  ExpectRejected<camera_pose_t>(&validator, "P", chop(pose, pose.size() - 9),
                                RejectCause::kTruncated, {"camera_pose_t.version"});
  ExpectRejected<camera_pose_t>(&validator, "P", chop(pose, pose.size() - kPoseCameraLength - 5),
                                RejectCause::kTruncated, {"camera_pose_t.camera"});
  ExpectRejected<camera_pose_t>(&validator, "P", {}, RejectCause::kTruncated, {});
  // An array length that points past the end of the buffer.
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  std::vector<uint8_t> buffer = Encode("E", extrinsics);
  ASSERT_EQ(GetInt32(buffer, ExtrinsicsNumSlavesOffset(extrinsics)), 2);
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), 1'000'000'000);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kTruncated,
                                   {"rig_extrinsics_t.num_slaves", "1000000000 elements"});
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), 3);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kTruncated, {});
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kTruncated), 10);
}

TEST(LcmValidation, Oversize) {
  MessageValidator validator(kNames);
  std::vector<uint8_t> buffer = Encode("P", MakePoseMsg());
  buffer.push_back(0);
  ExpectRejected<camera_pose_t>(&validator, "P", buffer, RejectCause::kOversize,
                                {"camera_pose_t.buffer", "1 bytes left over"});
  // One slave fewer announced than encoded: the second one is left over.
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  buffer = Encode("E", extrinsics);
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), 1);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kOversize,
                                   {"rig_extrinsics_t.buffer", "left over"});
  buffer = Encode("S", MakeStatusMsg());
  buffer.insert(buffer.end(), 100, 0xab);
  ExpectRejected<rig_status_t>(&validator, "S", buffer, RejectCause::kOversize,
                               {"100 bytes left over"});
}

TEST(LcmValidation, Malformed) {
  MessageValidator validator(kNames);
  std::vector<uint8_t> buffer = Encode("P", MakePoseMsg());
  PutInt32(&buffer, kPoseCameraLength, 0);  // a string length < 1
  ExpectRejected<camera_pose_t>(&validator, "P", buffer, RejectCause::kMalformed,
                                {"camera_pose_t.camera", "string length 0"});
  // The same in a nested string, which LCM's own decode meets (and throws on).
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  buffer = Encode("E", extrinsics);
  const size_t slave_name = ExtrinsicsNumSlavesOffset(extrinsics) + 4;
  ASSERT_EQ(GetInt32(buffer, slave_name), 5);  // "left" + NUL
  PutInt32(&buffer, slave_name, -3);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kMalformed,
                                   {"rig_extrinsics_t.buffer", "LCM decode failed"});
  // A NUL inside a camera name.
  buffer = Encode("P", MakePoseMsg());
  buffer[kPoseCameraLength + 4 + 1] = 0;  // "l\0ft"
  ExpectRejected<camera_pose_t>(&validator, "P", buffer, RejectCause::kMalformed,
                                {"camera_pose_t.camera", "NUL"});
}

TEST(LcmValidation, BadSize) {
  MessageValidator validator(kNames);
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  std::vector<uint8_t> buffer = Encode("E", extrinsics);
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), -1);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kBadSize,
                                   {"rig_extrinsics_t.num_slaves", "negative length -1"});
  const image_t image = MakeImageMsg();
  buffer = Encode("I", image);
  ASSERT_EQ(GetInt32(buffer, ImageSizeOffset(image)), 15);
  PutInt32(&buffer, ImageSizeOffset(image), -15);
  ExpectRejected<image_t>(&validator, "I", buffer, RejectCause::kBadSize,
                          {"image_t.size", "negative length"});
  // Consistent on the wire, inconsistent with width/height/stride.
  image_t short_image = image;
  short_image.data.pop_back();
  short_image.size = 14;
  ExpectRejected<image_t>(&validator, "I", RawEncode(short_image), RejectCause::kBadSize,
                          {"image_t.size", "14 bytes but stride x height = 15"});
  image_t narrow = image;
  narrow.pixel_format = "BGR3";
  ExpectRejected<image_t>(&validator, "I", RawEncode(narrow), RejectCause::kBadSize,
                          {"image_t.stride", "less than width 4 x 3 bytes"});
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kBadSize), 4);

  // In memory: an array length that disagrees with its vector is refused before LCM's encode
  // (which would read past the vector).
  rig_extrinsics_t mismatch = MakeExtrinsicsMsg();
  mismatch.num_slaves = 3;
  Expected<std::vector<uint8_t>> encoded = EncodeMessage("E", kNames, mismatch);
  ASSERT_FALSE(encoded.ok());
  EXPECT_THAT(encoded.error(),
              HasSubstr("E: rig_extrinsics_t.num_slaves: 3 but slaves has 2 elements (bad_size)"));
  rig_status_t status = MakeStatusMsg();
  status.num_cameras = 2;
  std::optional<Rejection> rejection = CheckMessage("S", kNames, &status);
  ASSERT_TRUE(rejection.has_value());
  EXPECT_EQ(rejection->cause, RejectCause::kBadSize);
  EXPECT_THAT(rejection->message, HasSubstr("rig_status_t.num_cameras"));
  image_t image_mismatch = MakeImageMsg();
  image_mismatch.size = 16;
  rejection = CheckMessage("I", kNames, &image_mismatch);
  ASSERT_TRUE(rejection.has_value());
  EXPECT_EQ(rejection->cause, RejectCause::kBadSize);
}

TEST(LcmValidation, NonFinite) {
  MessageValidator validator(kNames);
  camera_pose_t pose = MakePoseMsg();
  pose.C[1] = kNaN;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonFinite,
                                {"camera_pose_t.C[1]", "not finite"});
  pose = MakePoseMsg();
  pose.quality = kInf;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonFinite,
                                {"camera_pose_t.quality"});
  pose = MakePoseMsg();
  pose.q[3] = kNaN;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonFinite,
                                {"camera_pose_t.q[3]"});
  pose = MakePoseMsg();
  pose.covariance[20] = kNaN;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonFinite,
                                {"camera_pose_t.covariance[20]"});
  pose.has_covariance = false;  // then the covariance is not read
  EXPECT_TRUE(
      validator.Decode<camera_pose_t>("P", RawEncode(pose).data(), RawEncode(pose).size()).ok());
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].rot_std_deg = -kInf;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kNonFinite,
                                   {"rig_extrinsics_t.slaves[1].rot_std_deg"});
  rig_status_t status = MakeStatusMsg();
  status.cameras[2].fps = kNaN;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kNonFinite,
                               {"rig_status_t.cameras[2].fps"});
}

TEST(LcmValidation, NonUnitQuaternion) {
  MessageValidator validator(kNames);
  camera_pose_t pose = MakePoseMsg();
  for (double& v : pose.q) v *= 1.0 + 2e-6;  // just beyond kUnitTolerance
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonUnitQuaternion,
                                {"camera_pose_t.q", "is not 1 within 1e-06"});
  pose = MakePoseMsg();
  pose.q[0] = pose.q[1] = pose.q[2] = pose.q[3] = 0.0;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonUnitQuaternion,
                                {"|q| = 0"});
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[0].q[0] = 1.1;
  extrinsics.slaves[0].q[1] = extrinsics.slaves[0].q[2] = extrinsics.slaves[0].q[3] = 0;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics),
                                   RejectCause::kNonUnitQuaternion,
                                   {"rig_extrinsics_t.slaves[0].q", "|q| = 1.1"});
}

TEST(LcmValidation, UnknownCamera) {
  MessageValidator validator(kNames);
  ExpectRejected<camera_pose_t>(&validator, "RIGCAL_POSE_roof", RawEncode(MakePoseMsg("roof")),
                                RejectCause::kUnknownCamera,
                                {"camera_pose_t.camera", "camera 'roof' is not one of"});
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(MakePoseMsg("")),
                                RejectCause::kUnknownCamera, {"empty camera name"});
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.master = "left";  // a camera of the rig, but not its master
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics),
                                   RejectCause::kUnknownCamera,
                                   {"rig_extrinsics_t.master", "not the rig's master 'front'"});
  extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].name = "front";  // the master is no slave
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics),
                                   RejectCause::kUnknownCamera,
                                   {"rig_extrinsics_t.slaves[1].name", "the rig's slaves"});
  rig_status_t status = MakeStatusMsg();
  status.cameras[0].name = "roof";
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kUnknownCamera,
                               {"rig_status_t.cameras[0].name"});
  image_t image = MakeImageMsg();
  image.camera = "roof";
  ExpectRejected<image_t>(&validator, "I", RawEncode(image), RejectCause::kUnknownCamera,
                          {"image_t.camera"});

  // Without a table any name is accepted, except where the camera index is needed.
  MessageValidator any;
  const std::vector<uint8_t> roof = RawEncode(MakePoseMsg("roof"));
  EXPECT_TRUE(any.Decode<camera_pose_t>("P", roof.data(), roof.size()).ok());
  Expected<PoseMessage> pose = any.DecodeCameraPose("P", roof.data(), roof.size());
  ASSERT_FALSE(pose.ok());
  EXPECT_THAT(pose.error(), HasSubstr("P: camera_pose_t.camera: camera 'roof'"));
  EXPECT_EQ(any.stats().Rejected(RejectCause::kUnknownCamera), 1);
  EXPECT_EQ(any.stats().accepted, 1);
}

TEST(LcmValidation, OutOfRange) {
  MessageValidator validator(kNames);
  camera_pose_t pose = MakePoseMsg();
  pose.quality = 1.5;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kOutOfRange,
                                {"camera_pose_t.quality", "outside [0, 1]"});
  pose = MakePoseMsg();
  pose.t_ns = -5;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kOutOfRange,
                                {"camera_pose_t.t_ns"});
  pose = MakePoseMsg();
  pose.covariance[1] = 0.5;  // (0, 1) != (1, 0)
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kOutOfRange,
                                {"camera_pose_t.covariance", "not symmetric"});
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[0].flags = 64;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"rig_extrinsics_t.slaves[0].flags", "undefined bits 64"});
  extrinsics.slaves[0].flags = kFlagConverged | kFlagInitialising;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"exactly one of"});
  extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].planar_axis[2] = 0.5;  // PLANAR flag set: must be a unit axis
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"rig_extrinsics_t.slaves[1].planar_axis"});
  extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].name = "left";
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"appears twice"});
  rig_status_t status = MakeStatusMsg();
  status.cameras[1].vo_state = 7;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[1].vo_state", "outside [0, 3]"});
  status = MakeStatusMsg();
  status.sync_fill = 65;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.sync_fill"});
  image_t image = MakeImageMsg();
  image.encoding = 9;
  ExpectRejected<image_t>(&validator, "I", RawEncode(image), RejectCause::kOutOfRange,
                          {"image_t.encoding"});
  image = MakeImageMsg();
  image.pixel_format = "GRAY8";
  ExpectRejected<image_t>(&validator, "I", RawEncode(image), RejectCause::kOutOfRange,
                          {"image_t.pixel_format"});
}

TEST(LcmValidation, StatsSummaryCountsByCause) {
  MessageValidator validator(kNames);
  const std::vector<uint8_t> good = Encode("P", MakePoseMsg());
  EXPECT_TRUE(validator.Decode<camera_pose_t>("P", good.data(), good.size()).ok());
  EXPECT_TRUE(validator.DecodeCameraPose("P", good.data(), good.size()).ok());
  camera_pose_t bad = MakePoseMsg();
  bad.version = 3;
  const std::vector<uint8_t> wrong_version = RawEncode(bad);
  EXPECT_FALSE(validator.DecodeCameraPose("P", wrong_version.data(), wrong_version.size()).ok());
  bad = MakePoseMsg();
  bad.C[0] = kNaN;
  for (int i = 0; i < 2; ++i) {
    const std::vector<uint8_t> nan = RawEncode(bad);
    EXPECT_FALSE(validator.Decode<camera_pose_t>("P", nan.data(), nan.size()).ok());
  }
  EXPECT_EQ(validator.stats().Summary(), "accepted 2, rejected 3 (wrong_version 1, non_finite 2)");
  validator.ResetStats();
  EXPECT_EQ(validator.stats().Summary(), "accepted 0, rejected 0");
  EXPECT_FALSE(validator.stats().last_rejection.has_value());
}

// ---- Transport: in-process LCM and log files ----

class Receiver {
 public:
  explicit Receiver(CameraNames names) : validator(std::move(names)) {}

  void HandlePose(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    ++handled;
    Expected<PoseMessage> pose = validator.DecodeCameraPose(channel, rbuf->data, rbuf->data_size);
    if (pose) poses.push_back(std::move(pose).value());
  }
  void HandleExtrinsics(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    ++handled;
    Expected<rig_extrinsics_t> msg =
        validator.Decode<rig_extrinsics_t>(channel, rbuf->data, rbuf->data_size);
    if (msg) extrinsics.push_back(std::move(msg).value());
  }

  MessageValidator validator;
  int handled = 0;
  std::vector<PoseMessage> poses;
  std::vector<rig_extrinsics_t> extrinsics;
};

// LCM 1.3.1 has no lambda subscribe. Its member-function subscribe crashes when built with GCC 12
// and -fsanitize=vptr (RIGCAL_ASAN_ENABLED): GCC miscompiles the pointer-to-member call inside
// lcm-cpp-impl.hpp. subscribeFunction with a context pointer has no such call.
void OnPose(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Receiver* receiver) {
  receiver->HandlePose(rbuf, channel);
}
void OnExtrinsics(const lcm::ReceiveBuffer* rbuf, const std::string& channel, Receiver* receiver) {
  receiver->HandleExtrinsics(rbuf, channel);
}

TEST(LcmTransport, MemqPublishSubscribe) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  Receiver receiver(kNames);
  ASSERT_NE(lcm.subscribeFunction("RIGCAL_POSE_.*", &OnPose, &receiver), nullptr);
  ASSERT_NE(lcm.subscribeFunction(kExtrinsicsChannel, &OnExtrinsics, &receiver), nullptr);

  std::vector<std::string> sent_cameras;
  for (int k = 0; k < 6; ++k) {
    CameraPose pose;
    pose.camera = k % 3;
    pose.t_ns = 1'000'000 * k;
    pose.trigger_seq = k;
    pose.pose.C = Eigen::Vector3d(k, 0, 0);
    Expected<camera_pose_t> msg = CameraPoseToLcm(pose, kNames, 10 + k);
    ASSERT_TRUE(msg.ok()) << msg.error();
    const std::vector<uint8_t> buffer = Encode(PoseChannel(msg->camera), *msg);
    ASSERT_EQ(lcm.publish(PoseChannel(msg->camera), buffer.data(), buffer.size()), 0);
    sent_cameras.push_back(msg->camera);
  }
  RigCalibration result;
  result.master = "front";
  result.slaves = {MakeSlave("left"), MakeSlave("back")};
  Expected<rig_extrinsics_t> extrinsics = RigCalibrationToLcm(result, 99, 5'000'000);
  ASSERT_TRUE(extrinsics.ok()) << extrinsics.error();
  const std::vector<uint8_t> extrinsics_buffer = Encode(kExtrinsicsChannel, *extrinsics);
  ASSERT_EQ(lcm.publish(kExtrinsicsChannel, extrinsics_buffer.data(), extrinsics_buffer.size()), 0);
  // A corrupt pose and a message of the wrong type on a pose channel.
  std::vector<uint8_t> corrupt = Encode("P", MakePoseMsg());
  corrupt.resize(corrupt.size() - 3);
  ASSERT_EQ(lcm.publish("RIGCAL_POSE_left", corrupt.data(), corrupt.size()), 0);
  ASSERT_EQ(lcm.publish("RIGCAL_POSE_left", extrinsics_buffer.data(), extrinsics_buffer.size()), 0);
  ASSERT_EQ(lcm.publish("NOT_SUBSCRIBED", corrupt.data(), corrupt.size()), 0);

  constexpr int kExpected = 9;
  for (int tries = 0; receiver.handled < kExpected && tries < 100; ++tries) {
    ASSERT_GE(lcm.handleTimeout(100), 0);
  }
  // Drain whatever else is queued (a provider may or may not queue NOT_SUBSCRIBED).
  for (int i = 0; i < 5 && lcm.handleTimeout(10) > 0; ++i) {
  }
  EXPECT_EQ(receiver.handled, kExpected);
  ASSERT_EQ(receiver.poses.size(), 6u);
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(receiver.poses[k].pose.camera, k % 3);
    EXPECT_EQ(receiver.poses[k].pose.t_ns, 1'000'000 * k);
    EXPECT_EQ(receiver.poses[k].pose.trigger_seq, k);
    EXPECT_EQ(receiver.poses[k].pose.pose.C.x(), k);
    EXPECT_EQ(receiver.poses[k].utime, 10 + k);
  }
  ASSERT_EQ(receiver.extrinsics.size(), 1u);
  EXPECT_EQ(RawEncode(receiver.extrinsics[0]), extrinsics_buffer);
  EXPECT_EQ(receiver.validator.stats().accepted, 7);
  EXPECT_EQ(receiver.validator.stats().Rejected(RejectCause::kTruncated), 1);
  EXPECT_EQ(receiver.validator.stats().Rejected(RejectCause::kWrongType), 1);
  EXPECT_EQ(receiver.validator.stats().TotalRejected(), 2);
}

std::string TempLogPath(const std::string& name) {
  return ::testing::TempDir() + "rigcal_lcm_messages_test_" + std::to_string(getpid()) + "_" +
         name + ".lcmlog";
}

struct Event {
  std::string channel;
  std::vector<uint8_t> data;
};

// A recording: poses of every camera, an image, extrinsics and status now and then.
std::vector<Event> MakeRecording() {
  std::vector<Event> events;
  for (int k = 0; k < 12; ++k) {
    for (int cam = 0; cam < 3; ++cam) {
      CameraPose pose;
      pose.camera = cam;
      pose.t_ns = 33'000'000LL * k + cam;
      pose.trigger_seq = k;
      pose.segment = k / 6;
      pose.pose.q = AxisAngle(Eigen::Vector3d::UnitZ(), 0.01 * k);
      pose.pose.C = Eigen::Vector3d(0.1 * k, cam, 0);
      Expected<camera_pose_t> msg = CameraPoseToLcm(pose, kNames, 1000 + k);
      EXPECT_TRUE(msg.ok()) << msg.error();
      events.push_back({PoseChannel(kNames[cam]), Encode("P", *msg)});
    }
    if (k % 4 == 0) {
      image_t image = MakeImageMsg();
      image.t_ns = 33'000'000LL * k;
      events.push_back({ImageChannel("back"), Encode("I", image)});
    }
    if (k % 5 == 4) {
      rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
      extrinsics.t_ns = 33'000'000LL * k;
      events.push_back({kExtrinsicsChannel, Encode("E", extrinsics)});
      rig_status_t status = MakeStatusMsg();
      status.sync_sets_emitted = k;
      events.push_back({kStatusChannel, Encode("S", status)});
    }
  }
  return events;
}

// Reads every event of the log at `path` and decodes it by channel; returns the events.
std::vector<Event> ReadLog(const std::string& path, MessageValidator* validator,
                           std::vector<int64_t>* timestamps) {
  std::vector<Event> events;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  if (!log.good()) return events;
  int64_t previous_eventnum = -1;
  while (const lcm::LogEvent* event = log.readNextEvent()) {
    EXPECT_GT(event->eventnum, previous_eventnum);
    previous_eventnum = event->eventnum;
    if (timestamps) timestamps->push_back(event->timestamp);
    const auto* bytes = static_cast<const uint8_t*>(event->data);
    events.push_back({event->channel, std::vector<uint8_t>(bytes, bytes + event->datalen)});
    const std::string& ch = event->channel;
    bool ok = false;
    if (ch.rfind("RIGCAL_POSE_", 0) == 0) {
      ok = validator->DecodeCameraPose(ch, event->data, event->datalen).ok();
    } else if (ch.rfind("RIGCAL_IMAGE_", 0) == 0) {
      ok = validator->Decode<image_t>(ch, event->data, event->datalen).ok();
    } else if (ch == kExtrinsicsChannel) {
      ok = validator->Decode<rig_extrinsics_t>(ch, event->data, event->datalen).ok();
    } else if (ch == kStatusChannel) {
      ok = validator->Decode<rig_status_t>(ch, event->data, event->datalen).ok();
    }
    EXPECT_TRUE(ok) << ch << ": "
                    << (validator->stats().last_rejection
                            ? validator->stats().last_rejection->message
                            : "unknown channel");
  }
  return events;
}

void ExpectSameEvents(const std::vector<Event>& read, const std::vector<Event>& written) {
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_EQ(read[i].channel, written[i].channel) << "event " << i;
    EXPECT_EQ(read[i].data, written[i].data) << "event " << i;
  }
}

TEST(LcmTransport, LogFileRoundTrip) {
  const std::string path = TempLogPath("logfile");
  const std::vector<Event> written = MakeRecording();
  ASSERT_EQ(written.size(), 36u + 3u + 4u);
  {
    lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good()) << path;
    for (size_t i = 0; i < written.size(); ++i) {
      lcm::LogEvent event;
      event.eventnum = static_cast<int64_t>(i);
      event.timestamp = 1'000'000 + 10 * static_cast<int64_t>(i);
      event.channel = written[i].channel;
      event.datalen = static_cast<int32_t>(written[i].data.size());
      event.data = const_cast<uint8_t*>(written[i].data.data());
      ASSERT_EQ(log.writeEvent(&event), 0);
    }
  }
  MessageValidator validator(kNames);
  std::vector<int64_t> timestamps;
  const std::vector<Event> read = ReadLog(path, &validator, &timestamps);
  ExpectSameEvents(read, written);
  ASSERT_EQ(timestamps.size(), written.size());
  for (size_t i = 0; i < timestamps.size(); ++i) {
    EXPECT_EQ(timestamps[i], 1'000'000 + 10 * static_cast<int64_t>(i));
  }
  EXPECT_EQ(validator.stats().accepted, static_cast<int64_t>(written.size()));
  EXPECT_EQ(validator.stats().TotalRejected(), 0);

  // Reading twice gives the same events: replay is deterministic.
  MessageValidator again(kNames);
  ExpectSameEvents(ReadLog(path, &again, nullptr), written);
  EXPECT_EQ(std::remove(path.c_str()), 0);
}

TEST(LcmTransport, FileProviderWritesALog) {
  const std::string path = TempLogPath("provider");
  const std::vector<Event> written = MakeRecording();
  {
    lcm::LCM lcm("file://" + path + "?mode=w");
    ASSERT_TRUE(lcm.good()) << path;
    for (const Event& event : written) {
      ASSERT_EQ(lcm.publish(event.channel, event.data.data(), event.data.size()), 0);
    }
  }  // closes the log
  MessageValidator validator(kNames);
  ExpectSameEvents(ReadLog(path, &validator, nullptr), written);
  EXPECT_EQ(validator.stats().accepted, static_cast<int64_t>(written.size()));
  EXPECT_EQ(validator.stats().TotalRejected(), 0);
  EXPECT_EQ(std::remove(path.c_str()), 0);
}

}  // namespace
}  // namespace rigcal::tools
