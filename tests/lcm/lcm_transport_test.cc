// SPDX-License-Identifier: Apache-2.0
// The rigcal LCM messages on LCM itself: in-process publish/subscribe (memq://) and LCM log files,
// written directly and through the file:// provider. Never UDP multicast (docs/architecture.md "LCM").
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <utility>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::lcm::lcm_test {
namespace {

TEST(LcmTransport, ChannelNames) {
  EXPECT_EQ(PoseChannel("left"), "RIGCAL_POSE_left");
  EXPECT_EQ(ImageChannel("back"), "RIGCAL_IMAGE_back");
  EXPECT_STREQ(kExtrinsicsChannel, "RIGCAL_EXTRINSICS");
  EXPECT_STREQ(kStatusChannel, "RIGCAL_STATUS");
}

class Receiver {
 public:
  explicit Receiver(CameraNames names) : validator(std::move(names)) {}

  void HandlePose(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    ++handled;
    Expected<PoseMessage> pose = validator.DecodeCameraPose(channel, rbuf->data, rbuf->data_size);
    if (pose) poses.push_back(std::move(pose).value());
  }
  void HandleExtrinsics(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel) {
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
void OnPose(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, Receiver* receiver) {
  receiver->HandlePose(rbuf, channel);
}
void OnExtrinsics(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, Receiver* receiver) {
  receiver->HandleExtrinsics(rbuf, channel);
}

TEST(LcmTransport, MemqPublishSubscribe) {
  ::lcm::LCM lcm("memq://");
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
  return ::testing::TempDir() + "rigcal_lcm_transport_test_" + std::to_string(getpid()) + "_" +
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
  ::lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  if (!log.good()) return events;
  int64_t previous_eventnum = -1;
  while (const ::lcm::LogEvent* event = log.readNextEvent()) {
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
    ::lcm::LogFile log(path, "w");
    ASSERT_TRUE(log.good()) << path;
    for (size_t i = 0; i < written.size(); ++i) {
      ::lcm::LogEvent event;
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
    ::lcm::LCM lcm("file://" + path + "?mode=w");
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
}  // namespace rigcal::lcm::lcm_test
