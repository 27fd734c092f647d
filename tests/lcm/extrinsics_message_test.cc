// SPDX-License-Identifier: Apache-2.0
// rig_extrinsics_t: round trips, the flags and fields from a RigCalibration, and every rule of
// its CheckMessage.
#include "rigcal/lcm/extrinsics_message.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>
#include <string>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm::lcm_test {
namespace {

TEST(ExtrinsicsMessage, RoundTrip) {
  const rig_extrinsics_t back = ExpectRoundTrip(kExtrinsicsChannel, MakeExtrinsicsMsg());
  ASSERT_EQ(back.num_slaves, 2);
  ASSERT_EQ(back.slaves.size(), 2u);
  EXPECT_EQ(back.master, "front");
  EXPECT_EQ(back.slaves[0].name, "left");
  EXPECT_EQ(back.slaves[0].motions_used, 190);
  EXPECT_EQ(back.slaves[0].message, "converged: after 7 iterations");
  EXPECT_EQ(back.slaves[1].name, "back");
  EXPECT_EQ(back.slaves[0].state, slave_extrinsics_t::STATE_CONVERGED);
  EXPECT_EQ(back.slaves[1].state, slave_extrinsics_t::STATE_INITIALISING);
  EXPECT_EQ(back.slaves[1].flags, kWireFlagPlanar);
  EXPECT_EQ(back.slaves[1].planar_axis[2], 1.0);
}

TEST(ExtrinsicsMessage, EmptySlavesRoundTrip) {
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves.clear();
  extrinsics.num_slaves = 0;
  EXPECT_TRUE(ExpectRoundTrip(kExtrinsicsChannel, extrinsics).slaves.empty());
}

TEST(ExtrinsicsMessage, RigCalibrationToLcmSetsFlagsAndFields) {
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
  planar.state = SlaveState::kInitialising;
  planar.message = "all rotations about one axis";
  planar.observability.planar = true;
  planar.observability.planar_axis = Eigen::Vector3d(0, -2, 0);
  SlaveCalibration waiting = MakeSlave("up");
  waiting.termination = Termination::kInsufficientMotion;
  waiting.state = SlaveState::kInitialising;
  waiting.estimate.q = Eigen::Quaterniond(kNaN, kNaN, kNaN, kNaN);
  waiting.estimate.C = Eigen::Vector3d::Constant(kNaN);
  waiting.scales.clear();
  waiting.estimate.scale = kNaN;
  waiting.rot_std_deg = kInf;
  result.slaves = {general, translational, planar, waiting};

  EXPECT_EQ(WireFlagsOf(general), 0);
  EXPECT_EQ(WireFlagsOf(translational), kWireFlagTranslationalOnly);
  EXPECT_EQ(WireFlagsOf(planar), kWireFlagPlanar);
  EXPECT_EQ(WireFlagsOf(waiting), 0);
  SlaveCalibration no_convergence = general;
  no_convergence.termination = Termination::kNoConvergence;  // usable: linear estimate kept
  EXPECT_EQ(WireFlagsOf(no_convergence), 0);

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
  EXPECT_EQ(left.state, slave_extrinsics_t::STATE_CONVERGED);
  EXPECT_EQ(left.flags, 0);
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
  EXPECT_EQ(left.message, "solved: after 5 iterations");

  EXPECT_EQ(msg->slaves[1].flags, kWireFlagTranslationalOnly);

  const slave_extrinsics_t& right = msg->slaves[2];
  EXPECT_EQ(right.state, slave_extrinsics_t::STATE_INITIALISING);
  EXPECT_EQ(right.flags, kWireFlagPlanar);
  EXPECT_EQ(right.planar_axis[0], 0.0);
  EXPECT_EQ(right.planar_axis[1], -1.0);  // normalised
  EXPECT_EQ(right.planar_axis[2], 0.0);
  EXPECT_EQ(right.message, "degenerate: all rotations about one axis");

  const slave_extrinsics_t& up = msg->slaves[3];  // placeholders instead of NaN
  EXPECT_EQ(up.state, slave_extrinsics_t::STATE_INITIALISING);
  EXPECT_EQ(up.flags, 0);
  EXPECT_EQ(up.q[0], 1.0);
  EXPECT_EQ(up.q[1], 0.0);
  EXPECT_EQ(up.C[0], 0.0);
  EXPECT_EQ(up.scale, 1.0);
  EXPECT_EQ(up.segment, 0);
  // Unknown σ (infinite, or NaN: not computed) is -1 on the wire, never 0.
  EXPECT_EQ(up.rot_std_deg, -1.0);
  EXPECT_EQ(up.scale_std, -1.0);
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
TEST(ExtrinsicsMessage, AxisOffsetOfPlanarAndNearlyPlanarEstimates) {
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
  EXPECT_EQ(msg->slaves[0].flags, kWireFlagPlanar);
  EXPECT_EQ(msg->slaves[0].axis_offset_std, -1.0);
  EXPECT_EQ(msg->slaves[1].flags, kWireFlagPlanar | kWireFlagAxisFromPrior);
  EXPECT_EQ(msg->slaves[1].axis_offset_std, 0.03);
  EXPECT_EQ(msg->slaves[2].axis_offset_std, 0.0);
  EXPECT_EQ(msg->slaves[3].flags, 0);
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
  bad.slaves[3].flags |= kWireFlagAxisFromPrior;
  EXPECT_FALSE(EncodeMessage(kExtrinsicsChannel, names, bad).ok());
}

TEST(ExtrinsicsMessage, ClockOffsetOfFreeRunningSlaves) {
  SlaveCalibration estimated = MakeSlave("left");
  estimated.time_offset_s = 0.0402;
  estimated.time_offset_std_s = 0.0003;
  SlaveCalibration given = MakeSlave("back");
  given.time_offset_s = -0.015;
  SlaveCalibration synchronised = MakeSlave("right");
  RigCalibration result;
  result.master = "front";
  result.slaves = {estimated, given, synchronised};
  Expected<rig_extrinsics_t> msg = RigCalibrationToLcm(result, 1, 2);
  ASSERT_TRUE(msg.ok()) << msg.error();
  EXPECT_EQ(msg->slaves[0].time_offset_source, slave_extrinsics_t::TIME_OFFSET_ESTIMATED);
  EXPECT_EQ(msg->slaves[0].time_offset_s, 0.0402);
  EXPECT_EQ(msg->slaves[0].time_offset_std_s, 0.0003);
  EXPECT_EQ(msg->slaves[1].time_offset_source, slave_extrinsics_t::TIME_OFFSET_GIVEN);
  EXPECT_EQ(msg->slaves[1].time_offset_s, -0.015);
  EXPECT_EQ(msg->slaves[1].time_offset_std_s, -1.0);
  EXPECT_EQ(msg->slaves[2].time_offset_source, slave_extrinsics_t::TIME_OFFSET_NONE);
  EXPECT_EQ(msg->slaves[2].time_offset_s, 0.0);
  EXPECT_EQ(msg->slaves[2].time_offset_std_s, -1.0);
  const CameraNames names = {"front", "left", "back", "right"};
  Expected<std::vector<uint8_t>> buffer = EncodeMessage(kExtrinsicsChannel, names, *msg);
  ASSERT_TRUE(buffer.ok()) << buffer.error();
  MessageValidator validator(names);
  auto back =
      validator.Decode<rig_extrinsics_t>(kExtrinsicsChannel, buffer->data(), buffer->size());
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back->slaves[0].time_offset_s, 0.0402);
  // An undefined source, a σ below 0 other than -1, or negative jumps are refused.
  for (const auto& breaks : std::vector<std::function<void(slave_extrinsics_t*)>>{
           [](slave_extrinsics_t* s) { s->time_offset_source = 4; },
           [](slave_extrinsics_t* s) { s->time_offset_std_s = -0.5; },
           [](slave_extrinsics_t* s) { s->clock_jumps = -1; }}) {
    rig_extrinsics_t bad = *msg;
    breaks(&bad.slaves[0]);
    EXPECT_FALSE(EncodeMessage(kExtrinsicsChannel, names, bad).ok());
  }
}

TEST(ExtrinsicsMessage, RigCalibrationToLcmRejectsBrokenResults) {
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

TEST(ExtrinsicsMessage, RejectsBadSize) {
  MessageValidator validator(kNames);
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  std::vector<uint8_t> buffer = Encode("E", extrinsics);
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), -1);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kBadSize,
                                   {"rig_extrinsics_t.num_slaves", "negative length -1"});
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kBadSize), 1);

  // In memory: an array length that disagrees with its vector is refused before LCM's encode
  // (which would read past the vector).
  rig_extrinsics_t mismatch = MakeExtrinsicsMsg();
  mismatch.num_slaves = 3;
  Expected<std::vector<uint8_t>> encoded = EncodeMessage("E", kNames, mismatch);
  ASSERT_FALSE(encoded.ok());
  EXPECT_THAT(encoded.error(),
              HasSubstr("E: rig_extrinsics_t.num_slaves: 3 but slaves has 2 elements (bad_size)"));
}

TEST(ExtrinsicsMessage, RejectsNonFinite) {
  MessageValidator validator(kNames);
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].rot_std_deg = -kInf;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kNonFinite,
                                   {"rig_extrinsics_t.slaves[1].rot_std_deg"});
}

TEST(ExtrinsicsMessage, RejectsNonUnitQuaternion) {
  MessageValidator validator(kNames);
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[0].q[0] = 1.1;
  extrinsics.slaves[0].q[1] = extrinsics.slaves[0].q[2] = extrinsics.slaves[0].q[3] = 0;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics),
                                   RejectCause::kNonUnitQuaternion,
                                   {"rig_extrinsics_t.slaves[0].q", "|q| = 1.1"});
}

TEST(ExtrinsicsMessage, RejectsUnknownCamera) {
  MessageValidator validator(kNames);
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
}

TEST(ExtrinsicsMessage, RejectsOutOfRange) {
  MessageValidator validator(kNames);
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[0].flags = 64;
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"rig_extrinsics_t.slaves[0].flags", "undefined bits 64"});
  extrinsics.slaves[0].flags = 0;
  extrinsics.slaves[0].state = 4;  // one past STATE_DECALIBRATED
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"rig_extrinsics_t.slaves[0].state"});
  extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].planar_axis[2] = 0.5;  // PLANAR flag set: must be a unit axis
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"rig_extrinsics_t.slaves[1].planar_axis"});
  extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].name = "left";
  ExpectRejected<rig_extrinsics_t>(&validator, "E", RawEncode(extrinsics), RejectCause::kOutOfRange,
                                   {"appears twice"});
}

}  // namespace
}  // namespace rigcal::lcm::lcm_test
