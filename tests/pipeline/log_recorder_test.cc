// SPDX-License-Identifier: Apache-2.0
// LogRecorder and the image codec: frames of tapped devices land in the log as image_t that decode
// to the same pixels, gaps in a device's frame numbers are counted as drops, other messages are
// recorded beside them with non-decreasing timestamps, and a log cut by a crash reads back up to
// its last complete event.
#include "rigcal/pipeline/log_recorder.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/pipeline/capture_loops.h"
#include "rigcal/pipeline/image_codec.h"
#include "support/lcm_log_events.h"
#include "support/temp_dir.h"

namespace rigcal::pipeline {
namespace {

namespace fs = std::filesystem;

// A textured test image that differs per camera and frame.
cv::Mat TestImage(int camera, int64_t k, int width = 64, int height = 48) {
  cv::Mat image(height, width, CV_8UC1);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      image.at<uint8_t>(r, c) =
          static_cast<uint8_t>((r * 7 + c * 3 + k * 11 + camera * 50) ^ (c * r));
    }
  }
  return image;
}

// A device that returns the frames `seqs` (gaps = frames lost by the device), 50 ms apart.
class ScriptedDevice final : public capture::CameraDevice {
 public:
  ScriptedDevice(std::string name, int camera, std::vector<int64_t> seqs)
      : name_(std::move(name)), camera_(camera), seqs_(std::move(seqs)) {}
  const std::string& name() const override { return name_; }
  double frame_rate_hz() const override { return 20.0; }
  Expected<std::optional<capture::Frame>> Grab() override {
    if (next_ >= seqs_.size()) return std::optional<capture::Frame>();
    const int64_t seq = seqs_[next_++];
    capture::Frame frame;
    frame.camera = camera_;
    frame.seq = seq;
    frame.t_ns = 1'000'000'000 + seq * 50'000'000;
    frame.image = TestImage(camera_, seq);
    return std::optional<capture::Frame>(std::move(frame));
  }
  void Interrupt() override {}

 private:
  std::string name_;
  int camera_;
  std::vector<int64_t> seqs_;
  size_t next_ = 0;
};

TEST(ImageCodec, RoundTripsEveryEncoding) {
  capture::Frame frame;
  frame.t_ns = 123'456'789;
  frame.seq = 42;
  frame.image = TestImage(1, 3);
  for (const ImageEncoding encoding :
       {ImageEncoding::kRaw, ImageEncoding::kPng, ImageEncoding::kJpeg}) {
    SCOPED_TRACE(ToString(encoding));
    ImageEncodeOptions options;
    options.encoding = encoding;
    auto msg = FrameToImageMessage(frame, "cam1", 123456, options);
    ASSERT_TRUE(msg.ok()) << msg.error();
    EXPECT_EQ(msg->t_ns, frame.t_ns);
    EXPECT_EQ(msg->trigger_seq, 42);
    EXPECT_EQ(msg->pixel_format, "GREY");
    EXPECT_FALSE(lcm::CheckMessage(lcm::ImageChannel("cam1"), {"cam0", "cam1"}, &*msg).has_value());
    auto back = FrameFromImage(*msg, 0);
    ASSERT_TRUE(back.ok()) << back.error();
    ASSERT_EQ(back->image.size(), frame.image.size());
    EXPECT_EQ(back->t_ns, frame.t_ns);
    EXPECT_EQ(back->seq, 42);
    const double max_diff = cv::norm(back->image, frame.image, cv::NORM_INF);
    if (encoding == ImageEncoding::kJpeg) {
      EXPECT_GT(cv::mean(cv::abs(back->image - frame.image))[0], 0.0);  // lossy, but close
      EXPECT_LT(cv::norm(back->image, frame.image, cv::NORM_L1) / frame.image.total(), 12.0);
    } else {
      EXPECT_EQ(max_diff, 0.0);
    }
  }
  EXPECT_EQ(ParseImageEncoding("png"), ImageEncoding::kPng);
  EXPECT_FALSE(ParseImageEncoding("bmp").has_value());
}

TEST(ImageCodec, DecodesOtherRawFormatsAndRejectsBadData) {
  image_t msg{};
  msg.version = image_t::VERSION;
  msg.camera = "cam0";
  msg.width = 2;
  msg.height = 1;
  msg.encoding = image_t::ENCODING_RAW;
  msg.pixel_format = "BGR3";
  msg.stride = 8;                               // padded rows
  msg.data = {0, 0, 255, 255, 255, 255, 9, 9};  // red, white
  msg.size = 8;
  auto grey = FrameFromImage(msg, 0);
  ASSERT_TRUE(grey.ok()) << grey.error();
  EXPECT_EQ(grey->image.at<uint8_t>(0, 0), 76);  // 0.299 * 255
  EXPECT_EQ(grey->image.at<uint8_t>(0, 1), 255);
  msg.pixel_format = "Y16 ";
  msg.stride = 4;
  msg.data = {0x00, 0x80, 0xFF, 0xFF};  // little-endian 0x8000, 0xFFFF
  msg.size = 4;
  grey = FrameFromImage(msg, 0);
  ASSERT_TRUE(grey.ok()) << grey.error();
  EXPECT_EQ(grey->image.at<uint8_t>(0, 0), 128);
  EXPECT_EQ(grey->image.at<uint8_t>(0, 1), 255);
  msg.pixel_format = "NV12";
  grey = FrameFromImage(msg, 0);
  ASSERT_FALSE(grey.ok());
  EXPECT_NE(grey.error().find("'NV12' is not supported"), std::string::npos) << grey.error();
  msg.encoding = image_t::ENCODING_PNG;
  msg.data = {1, 2, 3, 4};
  grey = FrameFromImage(msg, 0);
  ASSERT_FALSE(grey.ok());
  EXPECT_NE(grey.error().find("do not decode as PNG"), std::string::npos) << grey.error();
}

struct LogContents {
  std::map<std::string, int> events_per_channel;
  std::vector<image_t> images;
  std::vector<int64_t> timestamps;
};

LogContents ReadLog(const std::string& path, const lcm::CameraNames& names) {
  LogContents contents;
  lcm::MessageValidator validator(names);
  for (const support::LoggedEvent& e : support::ReadLcmLog(path)) {
    ++contents.events_per_channel[e.channel];
    contents.timestamps.push_back(e.timestamp);
    if (e.channel.rfind("RIGCAL_IMAGE_", 0) == 0) {
      auto image = validator.Decode<image_t>(e.channel, e.data.data(), e.data.size());
      EXPECT_TRUE(image.ok()) << image.error();
      if (image) contents.images.push_back(*image);
    }
  }
  return contents;
}

TEST(LogRecorder, RecordsTappedFramesAndMessages) {
  const fs::path dir = support::FreshTempDir("log_recorder_frames");
  const std::string path = (dir / "rec.lcmlog").string();
  const lcm::CameraNames names = {"cam0", "cam1"};
  RecorderOptions options;
  options.image.encoding = ImageEncoding::kPng;
  options.lossless = true;
  auto recorder = LogRecorder::Open(path, names, options);
  ASSERT_TRUE(recorder.ok()) << recorder.error();
  std::vector<std::unique_ptr<capture::CameraDevice>> devices;
  devices.push_back((*recorder)->Tap(
      std::make_unique<ScriptedDevice>("cam0", 0, std::vector<int64_t>{0, 1, 2, 3, 4, 5}), 0));
  // cam1 loses frames 2 and 4..5.
  devices.push_back((*recorder)->Tap(
      std::make_unique<ScriptedDevice>("cam1", 1, std::vector<int64_t>{0, 1, 3, 6}), 1));
  CaptureLoops capture(std::move(devices));
  capture.Start();
  (*recorder)->Record("RIGCAL_EXTRINSICS", 0, {1, 2, 3});  // dated before every frame
  while (!capture.Finished()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  capture.Stop();
  ASSERT_TRUE((*recorder)->Stop().ok());
  const RecorderStats stats = (*recorder)->Stats();
  EXPECT_EQ(stats.frames, (std::vector<int64_t>{6, 4}));
  EXPECT_EQ(stats.dropped_capture, (std::vector<int64_t>{0, 3}));
  EXPECT_EQ(stats.dropped_disk, 0);
  EXPECT_EQ(stats.DroppedTotal(), 3);
  EXPECT_EQ(stats.other_events, 1);
  EXPECT_EQ(stats.files, std::vector<std::string>{path});
  EXPECT_EQ(stats.bytes, static_cast<int64_t>(fs::file_size(path)));

  const LogContents log = ReadLog(path, names);
  EXPECT_EQ(log.events_per_channel.at("RIGCAL_IMAGE_cam0"), 6);
  EXPECT_EQ(log.events_per_channel.at("RIGCAL_IMAGE_cam1"), 4);
  EXPECT_EQ(log.events_per_channel.at("RIGCAL_EXTRINSICS"), 1);
  for (size_t i = 1; i < log.timestamps.size(); ++i) {
    EXPECT_GE(log.timestamps[i], log.timestamps[i - 1]) << "event " << i;
  }
  for (const image_t& msg : log.images) {
    const int camera = msg.camera == "cam0" ? 0 : 1;
    EXPECT_EQ(msg.encoding, image_t::ENCODING_PNG);
    auto image = FrameFromImage(msg, 0);
    ASSERT_TRUE(image.ok()) << image.error();
    EXPECT_EQ(cv::norm(image->image, TestImage(camera, msg.trigger_seq), cv::NORM_INF), 0.0)
        << msg.camera << " frame " << msg.trigger_seq;
    EXPECT_EQ(msg.t_ns, 1'000'000'000 + msg.trigger_seq * 50'000'000);
  }
}

// A recording cut inside its last event (power loss) reads back up to the event before.
TEST(LogRecorder, CutRecordingReadsUpToLastCompleteEvent) {
  const fs::path dir = support::FreshTempDir("log_recorder_cut");
  const std::string path = (dir / "rec.lcmlog").string();
  const lcm::CameraNames names = {"cam0"};
  RecorderOptions options;
  options.lossless = true;
  auto recorder = LogRecorder::Open(path, names, options);
  ASSERT_TRUE(recorder.ok()) << recorder.error();
  std::vector<std::unique_ptr<capture::CameraDevice>> devices;
  devices.push_back((*recorder)->Tap(
      std::make_unique<ScriptedDevice>("cam0", 0, std::vector<int64_t>{0, 1, 2, 3, 4}), 0));
  CaptureLoops capture(std::move(devices));
  capture.Start();
  while (!capture.Finished()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  capture.Stop();
  ASSERT_TRUE((*recorder)->Stop().ok());
  const auto size = static_cast<int64_t>(fs::file_size(path));
  const int64_t event_bytes = size / 5;  // equal raw frames
  ASSERT_EQ(event_bytes * 5, size);
  fs::resize_file(path, static_cast<uintmax_t>(size - event_bytes / 2));
  const LogContents log = ReadLog(path, names);
  ASSERT_EQ(log.images.size(), 4u);
  EXPECT_EQ(log.images.back().trigger_seq, 3);
  auto image = FrameFromImage(log.images.back(), 0);
  ASSERT_TRUE(image.ok()) << image.error();
  EXPECT_EQ(cv::norm(image->image, TestImage(0, 3), cv::NORM_INF), 0.0);
}

TEST(LogRecorder, ReportsAnUnwritableLog) {
  const fs::path dir = support::FreshTempDir("log_recorder_unwritable");
  auto recorder = LogRecorder::Open((dir / "missing" / "rec.lcmlog").string(), {"cam0"}, {});
  ASSERT_FALSE(recorder.ok());
  EXPECT_NE(recorder.error().find("missing/rec.lcmlog"), std::string::npos) << recorder.error();
  RecorderOptions bad;
  bad.queue_events = 0;
  recorder = LogRecorder::Open((dir / "rec.lcmlog").string(), {"cam0"}, bad);
  ASSERT_FALSE(recorder.ok());
  EXPECT_NE(recorder.error().find("queue_events"), std::string::npos) << recorder.error();
}

}  // namespace
}  // namespace rigcal::pipeline
