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
  status.sync_fill = 65;
  ExpectRejected<rig_status_t>(&validator, "S", RawEncode(status), RejectCause::kOutOfRange,
                               {"rig_status_t.sync_fill"});
}

}  // namespace
}  // namespace rigcal::tools::lcm_test
