// SPDX-License-Identifier: Apache-2.0
// camera_pose_t: round trip, normalisation, conversion from and to CameraPose, and every rule of
// its CheckMessage.
#include "rigcal/lcm/pose_message.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm::lcm_test {
namespace {

TEST(PoseMessage, RoundTrip) {
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

TEST(PoseMessage, NearUnitQuaternionIsNormalised) {
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

TEST(PoseMessage, ConversionRoundTrip) {
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

TEST(PoseMessage, ConversionRejectsBadInput) {
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

TEST(PoseMessage, RejectsNonFinite) {
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
}

TEST(PoseMessage, RejectsNonUnitQuaternion) {
  MessageValidator validator(kNames);
  camera_pose_t pose = MakePoseMsg();
  for (double& v : pose.q) v *= 1.0 + 2e-6;  // just beyond kUnitTolerance
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonUnitQuaternion,
                                {"camera_pose_t.q", "is not 1 within 1e-06"});
  pose = MakePoseMsg();
  pose.q[0] = pose.q[1] = pose.q[2] = pose.q[3] = 0.0;
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(pose), RejectCause::kNonUnitQuaternion,
                                {"|q| = 0"});
}

TEST(PoseMessage, RejectsUnknownCamera) {
  MessageValidator validator(kNames);
  ExpectRejected<camera_pose_t>(&validator, "RIGCAL_POSE_roof", RawEncode(MakePoseMsg("roof")),
                                RejectCause::kUnknownCamera,
                                {"camera_pose_t.camera", "camera 'roof' is not one of"});
  ExpectRejected<camera_pose_t>(&validator, "P", RawEncode(MakePoseMsg("")),
                                RejectCause::kUnknownCamera, {"empty camera name"});

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

TEST(PoseMessage, RejectsOutOfRange) {
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
}

}  // namespace
}  // namespace rigcal::lcm::lcm_test
