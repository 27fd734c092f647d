// SPDX-License-Identifier: Apache-2.0
// rig_status_t: round trips and every rule of its CheckMessage.
#include "rigcal/lcm/status_message.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm::lcm_test {
namespace {

TEST(StatusMessage, RoundTrip) {
  const rig_status_t back = ExpectRoundTrip(kStatusChannel, MakeStatusMsg());
  ASSERT_EQ(back.cameras.size(), 3u);
  EXPECT_EQ(back.cameras[1].name, "left");
  EXPECT_EQ(back.cameras[1].dropped_never_matched, 6);
  EXPECT_EQ(back.cameras[2].vo_state, camera_status_t::VO_LOST);
  EXPECT_EQ(back.cameras[2].vo_segment, 4);
  EXPECT_EQ(back.cameras[2].relocalisations, 9);  // version 5
  EXPECT_EQ(back.estimator_state, rig_status_t::ESTIMATOR_DEGRADED);
  EXPECT_EQ(back.estimator_message, "back: insufficient motion");
  EXPECT_EQ(back.rss_bytes, 123'456'789);
}

TEST(StatusMessage, EmptyCamerasRoundTrip) {
  rig_status_t status = MakeStatusMsg();
  status.cameras.clear();
  status.num_cameras = 0;
  EXPECT_TRUE(ExpectRoundTrip(kStatusChannel, status).cameras.empty());
}

TEST(StatusMessage, RejectsBadSize) {
  rig_status_t status = MakeStatusMsg();
  status.num_cameras = 2;
  std::optional<Rejection> rejection = CheckMessage("S", kNames, &status);
  ASSERT_TRUE(rejection.has_value());
  EXPECT_EQ(rejection->cause, RejectCause::kBadSize);
  EXPECT_THAT(rejection->message, HasSubstr("rig_status_t.num_cameras"));
}

TEST(StatusMessage, RejectsNonFinite) {
  MessageValidator validator(kNames);
  rig_status_t status = MakeStatusMsg();
  status.cameras[2].fps = kNaN;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kNonFinite,
                               {"rig_status_t.cameras[2].fps"});
}

TEST(StatusMessage, RejectsUnknownCamera) {
  MessageValidator validator(kNames);
  rig_status_t status = MakeStatusMsg();
  status.cameras[0].name = "roof";
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kUnknownCamera,
                               {"rig_status_t.cameras[0].name"});
}

TEST(StatusMessage, RejectsOutOfRange) {
  MessageValidator validator(kNames);
  rig_status_t status = MakeStatusMsg();
  status.cameras[1].vo_state = 7;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[1].vo_state", "outside [0, 3]"});
  status = MakeStatusMsg();
  status.cameras[0].vo_segment = -2;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[0].vo_segment"});
  status = MakeStatusMsg();
  status.cameras[2].relocalisations = -1;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[2].relocalisations"});
  status = MakeStatusMsg();
  status.sync_fill = 65;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.sync_fill"});
}

// fps comes from the stamps: 20 frames 50 ms apart are 20 fps however fast they were replayed.
TEST(StatusMessage, RatesFromStampsNotTheWallClock) {
  StampRate rate;
  const int64_t t0 = 5'000'000'000;
  EXPECT_EQ(rate.Update(0, -1, -1), 0.0);  // nothing yet
  EXPECT_DOUBLE_EQ(rate.Update(20, t0 + 19 * 50'000'000, t0 - 50'000'000), 20.0);
  EXPECT_DOUBLE_EQ(rate.Update(30, t0 + 29 * 50'000'000, -1), 20.0);  // 10 more in 0.5 s
  EXPECT_EQ(rate.Update(30, t0 + 29 * 50'000'000, -1), 0.0);          // no new stamp
}

// A set dropped by a full ready queue shows as an overflow drop of every camera in it.
TEST(StatusMessage, ConsumerOverflowIsAnOverflowDrop) {
  SyncStats sync;
  sync.cameras.resize(2);
  sync.cameras[0].overflow = 2;
  sync.cameras[0].consumer_overflow = 5;
  sync.cameras[1].consumer_overflow = 4;
  std::vector<CameraStatusInput> cameras(2);
  cameras[0].name = kNames[0];
  cameras[1].name = kNames[1];
  cameras[1].dropped_backlog = 1;
  cameras[1].vo_segment = 3;
  cameras[1].relocalisations = 2;
  const rig_status_t msg = MakeRigStatus(cameras, sync, 64, RigEstimate{}, 0.0, 1);
  EXPECT_EQ(msg.cameras[0].dropped_overflow, 7);
  EXPECT_EQ(msg.cameras[1].dropped_overflow, 5);
  EXPECT_EQ(msg.cameras[0].vo_segment, -1);  // no pose yet
  EXPECT_EQ(msg.cameras[1].vo_segment, 3);
  EXPECT_EQ(msg.cameras[0].relocalisations, 0);
  EXPECT_EQ(msg.cameras[1].relocalisations, 2);
}

// Version 4: every camera's clock (offset, σ, drift, jumps) survives the wire; undefined sources,
// σ below -1, non-finite values and negative jump counts are rejected.
TEST(StatusMessage, ClockFieldsRoundTripAndAreChecked) {
  rig_status_t status = MakeStatusMsg();
  camera_status_t& left = status.cameras[1];
  left.time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATED;
  left.time_offset_s = -39.95;
  left.time_offset_std_s = 2.1e-4;
  left.clock_drift_ppm = 48.5;
  left.clock_drift_std_ppm = 1.5;
  left.clock_jumps = 2;
  const rig_status_t back = ExpectRoundTrip(kStatusChannel, status);
  EXPECT_EQ(back.version, rig_status_t::VERSION);
  EXPECT_EQ(back.cameras[1].time_offset_source, slave_extrinsics_t::TIME_OFFSET_ESTIMATED);
  EXPECT_EQ(back.cameras[1].time_offset_s, -39.95);
  EXPECT_EQ(back.cameras[1].time_offset_std_s, 2.1e-4);
  EXPECT_EQ(back.cameras[1].clock_drift_ppm, 48.5);
  EXPECT_EQ(back.cameras[1].clock_drift_std_ppm, 1.5);
  EXPECT_EQ(back.cameras[1].clock_jumps, 2);

  MessageValidator validator(kNames);
  rig_status_t bad = status;
  bad.cameras[1].time_offset_source = 4;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(bad), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[1].time_offset_source", "outside [0, 3]"});
  bad = status;
  bad.cameras[1].time_offset_std_s = -2.0;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(bad), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[1].time_offset_std_s"});
  bad = status;
  bad.cameras[1].clock_drift_ppm = kNaN;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(bad), RejectCause::kNonFinite,
                               {"rig_status_t.cameras[1].clock_drift_ppm"});
  bad = status;
  bad.cameras[1].clock_jumps = -1;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(bad), RejectCause::kOutOfRange,
                               {"rig_status_t.cameras[1].clock_jumps"});
}

// The clock fields come from the estimate: the master is the reference, an estimated offset
// carries its σ, drift and jumps, one still being estimated is 0 with σ unknown, a given one
// has no σ, synchronised stamps none.
TEST(StatusMessage, ClockFieldsFromTheEstimate) {
  RigEstimate estimate;
  estimate.rig.slaves.resize(3);
  estimate.online.resize(3);
  estimate.rig.slaves[0].time_offset_s = 0.040012;
  estimate.rig.slaves[0].time_offset_std_s = 2.1e-4;
  estimate.online[0].clock_offset_estimated = true;
  estimate.online[0].clock_offset_known = true;
  estimate.online[0].clock_drift_ppm = 50.2;
  estimate.online[0].clock_drift_std_ppm = 0.7;
  estimate.online[0].clock_jumps = 1;
  estimate.rig.slaves[1].time_offset_s = 0.5;  // stale: the offset is being re-estimated
  estimate.online[1].clock_offset_estimated = true;
  estimate.online[1].clock_jumps = 2;
  estimate.rig.slaves[2].time_offset_s = -0.025;  // given
  std::vector<CameraStatusInput> cameras(4);
  const rig_status_t msg = MakeRigStatus(cameras, SyncStats{}, 64, estimate, 0.0, 1);
  ASSERT_EQ(msg.cameras.size(), 4u);
  EXPECT_EQ(msg.cameras[0].time_offset_source, slave_extrinsics_t::TIME_OFFSET_NONE);
  EXPECT_EQ(msg.cameras[0].time_offset_std_s, -1.0);
  const camera_status_t& a = msg.cameras[1];
  EXPECT_EQ(a.time_offset_source, slave_extrinsics_t::TIME_OFFSET_ESTIMATED);
  EXPECT_EQ(a.time_offset_s, 0.040012);
  EXPECT_EQ(a.time_offset_std_s, 2.1e-4);
  EXPECT_EQ(a.clock_drift_ppm, 50.2);
  EXPECT_EQ(a.clock_drift_std_ppm, 0.7);
  EXPECT_EQ(a.clock_jumps, 1);
  const camera_status_t& b = msg.cameras[2];
  EXPECT_EQ(b.time_offset_source, slave_extrinsics_t::TIME_OFFSET_ESTIMATING);
  EXPECT_EQ(b.time_offset_s, 0.0);
  EXPECT_EQ(b.time_offset_std_s, -1.0);
  EXPECT_EQ(b.clock_jumps, 2);
  const camera_status_t& c = msg.cameras[3];
  EXPECT_EQ(c.time_offset_source, slave_extrinsics_t::TIME_OFFSET_GIVEN);
  EXPECT_EQ(c.time_offset_s, -0.025);
  EXPECT_EQ(c.time_offset_std_s, -1.0);
  EXPECT_EQ(
      MakeRigStatus(cameras, SyncStats{}, 64, RigEstimate{}, 0.0, 1).cameras[1].time_offset_source,
      slave_extrinsics_t::TIME_OFFSET_NONE);
}

}  // namespace
}  // namespace rigcal::lcm::lcm_test
