// The libcamera source on vimc (the kernel's virtual media-controller camera, built out of tree
// by scripts/vm/build-assets.sh; libcamera's vimc pipeline and IPA): the camera by model, the
// validated configuration, frames with sensor timestamps on CLOCK_MONOTONIC and increasing
// sensor sequence numbers, request recycling over more frames than buffers, clean stop; and
// camera removal: vimc unbound from its driver through sysfs (its nodes go away, udevd forwards
// the kernel's remove event to libcamera's device enumerator) is a device loss while a vivid
// camera keeps streaming, and the camera comes back when vimc is bound again.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <thread>

#include "guest_skip.h"
#include "rigcal/drivers/libcamera_device.h"
#include "rigcal/drivers/v4l2_device.h"
#include "rigcal/drivers/v4l2_timestamp.h"

namespace rigcal::drivers {
namespace {

LibcameraOptions VimcOptions(int width, int height) {
  LibcameraOptions options;
  options.camera = "Sensor B";  // vimc's camera model
  options.width = width;
  options.height = height;
  options.buffers = 4;
  return options;
}

TEST(LibcameraVimc, FramesWithSensorTimestampsAndCleanStop) {
  RIGCAL_REQUIRE_NODE("/dev/media0");
  auto cameras = ListLibcameraCameras();
  ASSERT_TRUE(cameras.ok()) << cameras.error();
  for (const std::string& c : *cameras) std::cout << "  libcamera camera: " << c << "\n";
  ASSERT_FALSE(cameras->empty()) << "libcamera sees no camera (udev data, IPA?)";

  // vimc's scaler works on multiples of its sizes: a size it will not deliver is an error that
  // names both sizes.
  auto odd = LibcameraDevice::Open("cam0", 0, VimcOptions(333, 111));
  if (!odd.ok()) {
    std::cout << "  333x111: " << odd.error() << "\n";
    EXPECT_NE(odd.error().find("camera model needs 333x111"), std::string::npos) << odd.error();
  }
  odd = Error{"released"};

  // vimc's debayer and scaler deliver 636x480 for its 640x480 sensor (validate() adjusts 640).
  auto device = LibcameraDevice::Open("cam0", 0, VimcOptions(636, 480));
  ASSERT_TRUE(device.ok()) << device.error();
  std::cout << "  configuration " << (*device)->configuration() << "; " << (*device)->validation()
            << "\n";
  constexpr int kFrames = 12;  // three times the buffers: requests are recycled
  int64_t last_t = -1;
  int64_t last_seq = -1;
  for (int i = 0; i < kFrames; ++i) {
    auto frame = (*device)->Grab();
    ASSERT_TRUE(frame.ok()) << frame.error();
    ASSERT_TRUE(frame->has_value());
    const Frame& f = **frame;
    const int64_t now = MonotonicNowNs();
    EXPECT_EQ(f.image.type(), CV_8UC1);
    EXPECT_EQ(f.image.cols, 636);
    EXPECT_EQ(f.image.rows, 480);
    cv::Scalar mean, stddev;
    cv::meanStdDev(f.image, mean, stddev);
    EXPECT_GT(stddev[0], 5.0) << "frame " << i << " is flat: vimc draws a test pattern";
    EXPECT_GE(now - f.t_ns, 0) << "stamp in the future: not CLOCK_MONOTONIC";
    EXPECT_LT(now - f.t_ns, 2'000'000'000) << "stamp too old: not CLOCK_MONOTONIC";
    EXPECT_GT(f.t_ns, last_t);
    EXPECT_GT(f.seq, last_seq);
    last_t = f.t_ns;
    last_seq = f.seq;
  }
  const LibcameraStats stats = (*device)->stats();
  EXPECT_TRUE(stats.sensor_timestamps) << "no SensorTimestamp in the request metadata";
  EXPECT_EQ(stats.frames, kFrames);
  std::cout << "  " << stats.frames << " frames, " << stats.sequence_drops << " drops, "
            << stats.failed_requests << " failed requests, last seq " << last_seq << "\n";

  auto blocked = std::async(std::launch::async, [&] {
    for (;;) {
      auto frame = (*device)->Grab();
      if (!frame.ok()) return std::string("error: ") + frame.error();
      if (!frame->has_value()) return std::string("stopped");
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  (*device)->Interrupt();
  ASSERT_EQ(blocked.wait_for(std::chrono::seconds(2)), std::future_status::ready);
  EXPECT_EQ(blocked.get(), "stopped");
}

TEST(LibcameraVimc, UnknownCameraNamesWhatThereIs) {
  RIGCAL_REQUIRE_NODE("/dev/media0");
  LibcameraOptions options = VimcOptions(640, 480);
  options.camera = "no such camera";
  auto device = LibcameraDevice::Open("cam7", 0, options);
  ASSERT_FALSE(device.ok());
  EXPECT_NE(device.error().find("cam7"), std::string::npos) << device.error();
  EXPECT_NE(device.error().find("Sensor B"), std::string::npos) << device.error();
}

constexpr char kVimcDriver[] = "/sys/bus/platform/drivers/vimc";

// The platform device vimc's driver is bound to ("vimc.0"), or "" when unbound.
std::string BoundVimcDevice() {
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(kVimcDriver, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("vimc", 0) == 0) return name;
  }
  return "";
}

bool WriteSysfs(const std::string& path, const std::string& value) {
  std::ofstream out(path);
  out << value;
  out.flush();
  return static_cast<bool>(out);
}

template <typename Predicate>
bool WaitFor(Predicate done, std::chrono::seconds limit) {
  const auto deadline = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

TEST(LibcameraVimc, RemovalIsADeviceLossTheOtherCameraStreamsAndTheCameraComesBack) {
  RIGCAL_REQUIRE_NODE("/dev/media0");
  RIGCAL_REQUIRE_NODE("/dev/video1");
  if (access("/run/udev/control", F_OK) != 0) {
    RIGCAL_SKIP_MISSING() << "no udevd in the guest (/run/udev/control): libcamera is not told "
                          << "about removed devices (scripts/vm/build-assets.sh packs Debian's "
                          << "udev when apt-get can download it)";
  }
  const std::string vimc = BoundVimcDevice();
  ASSERT_NE(vimc, "") << "vimc is not bound to its driver (" << kVimcDriver << ")";
  LibcameraOptions options = VimcOptions(636, 480);
  options.reconnect_max_backoff_s = 0.4;
  auto cam1 = LibcameraDevice::Open("cam1", 1, options);
  ASSERT_TRUE(cam1.ok()) << cam1.error();
  V4l2Options vivid;
  vivid.device = "bus:platform:vivid-000";
  vivid.width = 320;
  vivid.height = 180;
  vivid.formats = {PixelFormat::kGrey};
  auto cam0 = V4l2Device::Open("cam0", 0, vivid);
  ASSERT_TRUE(cam0.ok()) << cam0.error();

  std::atomic<int64_t> cam1_frames{0};
  std::atomic<int64_t> cam1_last_seq{-1};
  auto cam1_loop = std::async(std::launch::async, [&] {
    for (;;) {
      auto frame = (*cam1)->Grab();
      if (!frame.ok()) return frame.error();
      if (!frame->has_value()) return std::string();
      ++cam1_frames;
      cam1_last_seq = (*frame)->seq;
    }
  });
  struct InterruptOnExit {  // cam1's loop ends before the future's destructor waits for it
    LibcameraDevice* device;
    ~InterruptOnExit() { device->Interrupt(); }
  } stop_cam1{cam1->get()};
  auto grab_cam0 = [&](int n) {
    for (int i = 0; i < n; ++i) {
      auto frame = (*cam0)->Grab();
      if (!frame.ok() || !frame->has_value()) return i;
    }
    return n;
  };
  ASSERT_EQ(grab_cam0(5), 5);
  ASSERT_TRUE(WaitFor([&] { return cam1_frames.load() >= 3; }, std::chrono::seconds(10)));

  ASSERT_TRUE(WriteSysfs(std::string(kVimcDriver) + "/unbind", vimc)) << "unbinding " << vimc;
  const bool noticed =
      WaitFor([&] { return (*cam1)->stats().removals > 0; }, std::chrono::seconds(10));
  const int64_t frames_at_loss = cam1_frames.load();
  const int64_t seq_at_loss = cam1_last_seq.load();
  // The other camera keeps streaming while vimc is gone.
  const int cam0_during = grab_cam0(10);
  const bool rebound = WriteSysfs(std::string(kVimcDriver) + "/bind", vimc);
  ASSERT_TRUE(noticed) << "libcamera did not report the removal of " << vimc;
  EXPECT_EQ(cam0_during, 10) << "the vivid camera stopped while vimc was gone";
  ASSERT_TRUE(rebound) << "binding " << vimc << " again";
  const bool resumed =
      WaitFor([&] { return cam1_frames.load() >= frames_at_loss + 5; }, std::chrono::seconds(30));
  (*cam1)->Interrupt();
  EXPECT_EQ(cam1_loop.get(), "") << "cam1 failed instead of reconnecting";
  const LibcameraStats stats = (*cam1)->stats();
  std::cout << "  cam1: " << stats.removals << " removal, " << stats.reconnections
            << " reconnection, " << stats.frames << " frames (" << frames_at_loss
            << " before the removal), last seq " << cam1_last_seq.load() << "\n";
  EXPECT_TRUE(resumed) << "cam1 did not deliver frames after vimc came back";
  EXPECT_EQ(stats.removals, 1);
  EXPECT_EQ(stats.reconnections, 1);
  EXPECT_GT(cam1_last_seq.load(), seq_at_loss);
}

}  // namespace
}  // namespace rigcal::drivers
