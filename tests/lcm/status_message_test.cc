// rig_status_t: round trips and every rule of its CheckMessage.
#include "rigcal/lcm/status_message.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::tools::lcm_test {
namespace {

TEST(StatusMessage, RoundTrip) {
  const rig_status_t back = ExpectRoundTrip(kStatusChannel, MakeStatusMsg());
  ASSERT_EQ(back.cameras.size(), 3u);
  EXPECT_EQ(back.cameras[1].name, "left");
  EXPECT_EQ(back.cameras[1].dropped_never_matched, 6);
  EXPECT_EQ(back.cameras[2].vo_state, camera_status_t::VO_LOST);
  EXPECT_EQ(back.cameras[2].vo_segment, 4);
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
  const rig_status_t msg = MakeRigStatus(cameras, sync, 64, RigEstimate{}, 0.0, 1);
  EXPECT_EQ(msg.cameras[0].dropped_overflow, 7);
  EXPECT_EQ(msg.cameras[1].dropped_overflow, 5);
  EXPECT_EQ(msg.cameras[0].vo_segment, -1);  // no pose yet
  EXPECT_EQ(msg.cameras[1].vo_segment, 3);
}

}  // namespace
}  // namespace rigcal::tools::lcm_test
