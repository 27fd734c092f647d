// SPDX-License-Identifier: Apache-2.0
// The V4L2 source on two vivid devices (the kernel's virtual video driver, loaded by
// scripts/vm/guest-init.sh with n_devs=2, webcam input): formats, CLOCK_MONOTONIC stamps,
// sequence continuity, two devices at once, clean stop, device loss (vivid's "Disconnect"
// control unregisters one device's nodes) while the other keeps streaming, and reconnection
// after the driver is reloaded.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <future>
#include <thread>
#include <vector>

#include "guest_skip.h"
#include "rigcal/capture/v4l2_device.h"
#include "rigcal/capture/v4l2_timestamp.h"

namespace rigcal::capture {
namespace {

constexpr int kWidth = 320;  // vivid's smallest webcam size
constexpr int kHeight = 180;
constexpr double kRateHz = 25.0;

V4l2Options Options(const std::string& device, PixelFormat format) {
  V4l2Options options;
  options.device = device;
  options.width = kWidth;
  options.height = kHeight;
  options.formats = {format};
  options.frame_rate_hz = kRateHz;
  options.buffers = 4;
  options.reconnect_max_backoff_s = 0.4;
  return options;
}

std::unique_ptr<V4l2Device> OpenOrFail(const std::string& name, int index,
                                       const V4l2Options& options) {
  auto device = V4l2Device::Open(name, index, options);
  EXPECT_TRUE(device.ok()) << device.error();
  return device.ok() ? std::move(*device) : nullptr;
}

struct Grabbed {
  std::vector<Frame> frames;
  std::vector<int64_t> grab_ns;  // CLOCK_MONOTONIC when Grab returned
  std::string error;
};

Grabbed GrabFrames(V4l2Device* device, int count) {
  Grabbed out;
  while (static_cast<int>(out.frames.size()) < count) {
    auto frame = device->Grab();
    if (!frame.ok()) {
      out.error = frame.error();
      break;
    }
    if (!frame->has_value()) break;
    out.grab_ns.push_back(MonotonicNowNs());
    out.frames.push_back(std::move(**frame));
  }
  return out;
}

// The checks every captured stream must pass.
void ExpectGoodStream(const Grabbed& g, const V4l2Device& device, int count) {
  ASSERT_TRUE(g.error.empty()) << g.error;
  ASSERT_EQ(static_cast<int>(g.frames.size()), count);
  std::vector<int64_t> periods;
  for (size_t i = 0; i < g.frames.size(); ++i) {
    const Frame& f = g.frames[i];
    EXPECT_EQ(f.image.type(), CV_8UC1);
    EXPECT_EQ(f.image.cols, kWidth);
    EXPECT_EQ(f.image.rows, kHeight);
    cv::Scalar mean, stddev;
    cv::meanStdDev(f.image, mean, stddev);
    EXPECT_GT(stddev[0], 5.0) << "frame " << i << " is flat: vivid draws colour bars";
    // CLOCK_MONOTONIC stamps. vivid stamps a frame with its nominal schedule, which its
    // thread may run ahead of by up to one frame period.
    const int64_t age_ns = g.grab_ns[i] - f.t_ns;
    EXPECT_GE(age_ns, -1'000'000'000 / kRateHz) << "frame " << i << " stamped in the future";
    EXPECT_LT(age_ns, 2'000'000'000) << "frame " << i << " stamp is not CLOCK_MONOTONIC";
    if (i > 0) {
      EXPECT_GT(f.t_ns, g.frames[i - 1].t_ns);
      EXPECT_GT(f.seq, g.frames[i - 1].seq);
      periods.push_back(f.t_ns - g.frames[i - 1].t_ns);
    }
  }
  // Sequence continuity: every number between the first and last frame was either delivered or
  // counted as a drop.
  const V4l2Stats stats = device.stats();
  const int64_t span = g.frames.back().seq - g.frames.front().seq + 1;
  EXPECT_EQ(span, static_cast<int64_t>(g.frames.size()) + stats.sequence_drops)
      << "sequence gaps not all counted";
  std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
  const double median_ms = periods[periods.size() / 2] / 1e6;
  std::cout << "  " << device.name() << " " << FourccText(device.negotiated().fourcc)
            << ": median period " << median_ms << " ms, " << stats.sequence_drops << " drops over "
            << span << " frames\n";
  // vivid stamps frames at its nominal rate; emulation jitters single frames, not the median.
  EXPECT_NEAR(median_ms, 1000.0 / kRateHz, 0.3 * 1000.0 / kRateHz);
}

TEST(Vivid, FindsDevicesByBusInfoAndCard) {
  RIGCAL_REQUIRE_NODE("/dev/video0");
  // Both vivid instances are called "vivid": the first capture node with that card.
  auto by_card = V4l2Device::Open("card", 0, Options("card:vivid", PixelFormat::kGrey));
  ASSERT_TRUE(by_card.ok()) << by_card.error();
  EXPECT_EQ((*by_card)->negotiated().bus_info, "platform:vivid-000");
  by_card = Error{"closed"};
  auto missing =
      V4l2Device::Open("cam9", 0, Options("bus:platform:nothing-here", PixelFormat::kGrey));
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("cam9"), std::string::npos) << missing.error();
  EXPECT_NE(missing.error().find("platform:vivid-000"), std::string::npos) << missing.error();
  auto no_mjpeg = V4l2Device::Open("cam0", 0, Options("/dev/video0", PixelFormat::kMjpeg));
  ASSERT_FALSE(no_mjpeg.ok());
  EXPECT_NE(no_mjpeg.error().find("none of the pixel formats MJPEG"), std::string::npos)
      << no_mjpeg.error();
}

TEST(Vivid, EveryOfferedFormatConverts) {
  RIGCAL_REQUIRE_NODE("/dev/video0");
  int converted = 0;
  for (PixelFormat format : {PixelFormat::kGrey, PixelFormat::kY10, PixelFormat::kY16,
                             PixelFormat::kYuyv, PixelFormat::kNv12}) {
    auto device = V4l2Device::Open("cam0", 0, Options("bus:platform:vivid-000", format));
    if (!device.ok()) {
      std::cout << "  " << ToString(format) << ": " << device.error() << "\n";
      // vivid offers these for its webcam input.
      EXPECT_TRUE(format != PixelFormat::kGrey && format != PixelFormat::kYuyv &&
                  format != PixelFormat::kNv12)
          << device.error();
      continue;
    }
    const Grabbed g = GrabFrames(device->get(), 3);
    ASSERT_TRUE(g.error.empty()) << g.error;
    ASSERT_EQ(g.frames.size(), 3u);
    cv::Scalar mean, stddev;
    cv::meanStdDev(g.frames.back().image, mean, stddev);
    EXPECT_GT(stddev[0], 5.0) << ToString(format);
    std::cout << "  " << ToString(format) << ": mean grey " << mean[0] << ", std " << stddev[0]
              << "\n";
    ++converted;
  }
  EXPECT_GE(converted, 3);
}

TEST(Vivid, TwoDevicesAtOnceAndCleanStop) {
  RIGCAL_REQUIRE_NODE("/dev/video1");
  auto cam0 = OpenOrFail("cam0", 0, Options("bus:platform:vivid-000", PixelFormat::kGrey));
  auto cam1 = OpenOrFail("cam1", 1, Options("bus:platform:vivid-001", PixelFormat::kYuyv));
  ASSERT_TRUE(cam0 && cam1);
  EXPECT_NEAR(cam0->frame_rate_hz(), kRateHz, 1e-6);
  constexpr int kFrames = 40;
  auto a = std::async(std::launch::async, [&] { return GrabFrames(cam0.get(), kFrames); });
  auto b = std::async(std::launch::async, [&] { return GrabFrames(cam1.get(), kFrames); });
  const Grabbed ga = a.get();
  const Grabbed gb = b.get();
  ExpectGoodStream(ga, *cam0, kFrames);
  ExpectGoodStream(gb, *cam1, kFrames);
  EXPECT_EQ(ga.frames.front().camera, 0);
  EXPECT_EQ(gb.frames.front().camera, 1);
  // The two free-running devices overlap in time.
  EXPECT_LT(std::max(ga.frames.front().t_ns, gb.frames.front().t_ns),
            std::min(ga.frames.back().t_ns, gb.frames.back().t_ns));

  // Clean stop: a Grab blocked in poll returns nothing promptly after Interrupt.
  auto blocked = std::async(std::launch::async, [&] {
    for (;;) {
      auto frame = cam0->Grab();
      if (!frame.ok()) return std::string("error: ") + frame.error();
      if (!frame->has_value()) return std::string("stopped");
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const int64_t interrupted_at = MonotonicNowNs();
  cam0->Interrupt();
  ASSERT_EQ(blocked.wait_for(std::chrono::seconds(2)), std::future_status::ready);
  EXPECT_EQ(blocked.get(), "stopped");
  EXPECT_LT(MonotonicNowNs() - interrupted_at, 1'000'000'000);
  auto after = cam0->Grab();
  ASSERT_TRUE(after.ok());
  EXPECT_FALSE(after->has_value());
}

// Presses vivid's "Disconnect" button control of `node`: the driver unregisters the device's
// nodes as a USB camera that is unplugged.
void PressDisconnect(const std::string& node) {
  const int fd = open(node.c_str(), O_RDWR | O_NONBLOCK);
  ASSERT_GE(fd, 0) << node << ": " << std::strerror(errno);
  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  bool pressed = false;
  while (ioctl(fd, VIDIOC_QUERYCTRL, &query) == 0) {
    if (std::string(reinterpret_cast<const char*>(query.name)) == "Disconnect") {
      v4l2_control control{};
      control.id = query.id;
      control.value = 1;
      EXPECT_EQ(ioctl(fd, VIDIOC_S_CTRL, &control), 0) << std::strerror(errno);
      pressed = true;
      break;
    }
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  close(fd);
  ASSERT_TRUE(pressed) << node << " has no Disconnect control";
}

TEST(Vivid, DeviceLossIsReportedTheOtherKeepsStreamingAndTheDeviceComesBack) {
  RIGCAL_REQUIRE_NODE("/dev/video1");
  auto cam0 = OpenOrFail("cam0", 0, Options("bus:platform:vivid-000", PixelFormat::kGrey));
  auto cam1 = OpenOrFail("cam1", 1, Options("bus:platform:vivid-001", PixelFormat::kGrey));
  ASSERT_TRUE(cam0 && cam1);
  const std::string node1 = cam1->negotiated().node;

  // cam1 grabs until it is interrupted; the frames it got and the last error, if any.
  std::atomic<int64_t> cam1_frames{0};
  std::atomic<int64_t> cam1_last_seq{-1};
  auto cam1_loop = std::async(std::launch::async, [&] {
    for (;;) {
      auto frame = cam1->Grab();
      if (!frame.ok()) return frame.error();
      if (!frame->has_value()) return std::string();
      ++cam1_frames;
      cam1_last_seq = (*frame)->seq;
    }
  });
  // Whatever fails below, cam1's loop ends before the future's destructor waits for it.
  struct InterruptOnExit {
    V4l2Device* device;
    ~InterruptOnExit() { device->Interrupt(); }
  } stop_cam1{cam1.get()};
  ASSERT_EQ(GrabFrames(cam0.get(), 10).frames.size(), 10u);
  ASSERT_GT(cam1_frames.load(), 3);

  PressDisconnect(node1);
  // The loss is noticed within a few frame periods.
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (cam1->stats().device_losses == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const V4l2Stats lost = cam1->stats();
  EXPECT_EQ(lost.device_losses, 1) << "the unplugged device was not noticed";
  EXPECT_FALSE(lost.connected);
  std::cout << "  cam1 lost: " << lost.last_loss << "\n";
  const int64_t frames_at_loss = cam1_frames.load();
  const int64_t seq_at_loss = cam1_last_seq.load();

  // cam0 keeps streaming meanwhile.
  const Grabbed after = GrabFrames(cam0.get(), 15);
  EXPECT_TRUE(after.error.empty()) << after.error;
  EXPECT_EQ(after.frames.size(), 15u);

  // vivid keeps the node of a "disconnected" instance open to new users: cam1 reconnects by its
  // bus info on its own, and its sequence numbers keep increasing.
  const auto back_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (cam1_frames.load() < frames_at_loss + 10 &&
         std::chrono::steady_clock::now() < back_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  cam1->Interrupt();
  EXPECT_EQ(cam1_loop.get(), "") << "cam1 failed instead of reconnecting";
  const V4l2Stats back = cam1->stats();
  EXPECT_EQ(back.reconnections, 1);
  EXPECT_GE(cam1_frames.load(), frames_at_loss + 10) << "cam1 did not resume after reconnecting";
  EXPECT_GT(cam1_last_seq.load(), seq_at_loss);
  std::cout << "  cam1: " << back.device_losses << " loss, " << back.reconnections
            << " reconnection, " << back.frames << " frames\n";
}

TEST(Vivid, WithoutReconnectALossIsAnError) {
  RIGCAL_REQUIRE_NODE("/dev/video1");
  auto options = Options("bus:platform:vivid-001", PixelFormat::kGrey);
  options.reconnect = false;
  auto cam1 = OpenOrFail("cam1", 1, options);
  ASSERT_TRUE(cam1);
  ASSERT_EQ(GrabFrames(cam1.get(), 3).frames.size(), 3u);
  PressDisconnect(cam1->negotiated().node);
  std::string error;
  for (int i = 0; i < 100 && error.empty(); ++i) {
    auto frame = cam1->Grab();
    if (!frame.ok()) error = frame.error();
  }
  EXPECT_NE(error.find("camera cam1: device bus:platform:vivid-001 lost"), std::string::npos)
      << error;
}

TEST(Vivid, ControlsFromOptions) {
  RIGCAL_REQUIRE_NODE("/dev/video0");
  auto options = Options("bus:platform:vivid-000", PixelFormat::kGrey);
  options.gain = 77;
  options.controls["brightness"] = 140;
  auto cam = OpenOrFail("cam0", 0, options);
  ASSERT_TRUE(cam);
  const int fd = open(cam->negotiated().node.c_str(), O_RDWR | O_NONBLOCK);
  ASSERT_GE(fd, 0);
  for (auto [id, value] : {std::pair<uint32_t, int>{V4L2_CID_GAIN, 77},
                           std::pair<uint32_t, int>{V4L2_CID_BRIGHTNESS, 140}}) {
    v4l2_control control{};
    control.id = id;
    ASSERT_EQ(ioctl(fd, VIDIOC_G_CTRL, &control), 0) << std::strerror(errno);
    EXPECT_EQ(control.value, value);
  }
  close(fd);
  cam.reset();  // the node streams until then: another S_FMT would be refused
  options.controls = {{"no_such_control", 1}};
  auto unknown = V4l2Device::Open("cam0", 0, options);
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().find("controls.no_such_control: the driver has no such control"),
            std::string::npos)
      << unknown.error();
  options.controls.clear();
  options.external_trigger = true;
  auto trigger = V4l2Device::Open("cam0", 0, options);
  ASSERT_FALSE(trigger.ok());
  EXPECT_NE(trigger.error().find("external_trigger: the driver offers no trigger control"),
            std::string::npos)
      << trigger.error();
}

}  // namespace
}  // namespace rigcal::capture
