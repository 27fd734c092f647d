// Capture latency and CPU of the V4L2 source per camera, on v4l2loopback: unlike vivid, which
// stamps a frame with its nominal schedule (up to a period ahead of delivery), v4l2loopback
// stamps a buffer when its writer writes it, so "now - stamp" when Grab returns is the whole
// capture path: the driver handing the buffer over, poll wake-up, DQBUF, conversion to grey
// and requeueing. The pipeline's capture loop pushes the frame into the camera's VO queue right
// after Grab returns, so this is the latency from the DQBUF stamp to the frame in the VO queue.
// Per camera (cam0 GREY, cam1 YUYV, 320x240): frames, drops, latency median / p99 / max, CPU of
// its capture thread (RUSAGE_THREAD). Under emulation (QEMU TCG) every figure is the emulated
// machine's. Checked: every stamp lies between the start of the write of its frame and the end
// of Grab (the driver stamps at the write), frames arrive (90 % of those written), no loss.
// Length: RIGCAL_DEVICE_LATENCY_S seconds (default 10) at 15 frames per second.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <future>
#include <mutex>
#include <opencv2/core.hpp>
#include <thread>
#include <vector>

#include "guest_skip.h"
#include "loopback_writer.h"
#include "rigcal/drivers/v4l2_device.h"
#include "rigcal/drivers/v4l2_timestamp.h"

namespace rigcal::drivers {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kRateHz = 15.0;

struct CameraRun {
  std::vector<int64_t> stamp_ns;  // the frame's kernel stamp
  std::vector<int64_t> grab_ns;   // when Grab returned it
  double cpu_s = 0.0;
  std::string error;
};

double ThreadCpuSeconds() {
  rusage r{};
  getrusage(RUSAGE_THREAD, &r);
  return r.ru_utime.tv_sec + r.ru_utime.tv_usec / 1e6 + r.ru_stime.tv_sec +
         r.ru_stime.tv_usec / 1e6;
}

CameraRun Capture(V4l2Device* device) {
  CameraRun out;
  const double cpu_before = ThreadCpuSeconds();
  for (;;) {
    auto frame = device->Grab();
    const int64_t now = MonotonicNowNs();
    if (!frame.ok()) {
      out.error = frame.error();
      break;
    }
    if (!frame->has_value()) break;
    out.stamp_ns.push_back((*frame)->t_ns);
    out.grab_ns.push_back(now);
  }
  out.cpu_s = ThreadCpuSeconds() - cpu_before;
  return out;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

TEST(LoopbackLatency, StampedAtTheWriteLatencyAndCpuPerCamera) {
  RIGCAL_REQUIRE_NODE("/dev/video20");
  RIGCAL_REQUIRE_NODE("/dev/video21");
  const char* env = std::getenv("RIGCAL_DEVICE_LATENCY_S");
  const double seconds = env ? std::atof(env) : 10.0;
  const char* nodes[] = {"/dev/video20", "/dev/video21"};
  const PixelFormat formats[] = {PixelFormat::kGrey, PixelFormat::kYuyv};
  std::vector<std::unique_ptr<LoopbackWriter>> writers;
  std::vector<std::vector<std::vector<uint8_t>>> packed(2);
  cv::RNG rng(7);
  // When each camera's writes started and ended.
  std::vector<std::vector<int64_t>> write_ns(2), write_end_ns(2);
  for (int i = 0; i < 2; ++i) {
    writers.push_back(std::make_unique<LoopbackWriter>(nodes[i], formats[i], kWidth, kHeight));
    ASSERT_EQ(writers[i]->error(), "");
    for (int k = 0; k < 4; ++k) {
      cv::Mat image(kHeight, kWidth, CV_8UC1);
      rng.fill(image, cv::RNG::UNIFORM, 0, 256);
      packed[i].push_back(writers[i]->Pack(image));
    }
    write_ns[i].push_back(MonotonicNowNs());
    ASSERT_TRUE(writers[i]->Write(packed[i][0])) << writers[i]->error();  // offers the format
    write_end_ns[i].push_back(MonotonicNowNs());
  }
  std::vector<std::unique_ptr<V4l2Device>> devices;
  for (int i = 0; i < 2; ++i) {
    V4l2Options options;
    options.device = nodes[i];
    options.width = kWidth;
    options.height = kHeight;
    options.formats = {formats[i]};
    options.buffers = 4;
    auto device = V4l2Device::Open("cam" + std::to_string(i), i, options);
    ASSERT_TRUE(device.ok()) << device.error();
    devices.push_back(std::move(*device));
  }
  std::vector<std::future<CameraRun>> runs;
  for (auto& device : devices) {
    runs.push_back(std::async(std::launch::async, [&device] { return Capture(device.get()); }));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // both streaming

  const int frames = static_cast<int>(seconds * kRateHz);
  const int64_t period_ns = static_cast<int64_t>(1e9 / kRateHz);
  int64_t next = MonotonicNowNs();
  bool written = true;
  for (int k = 0; k < frames && written; ++k) {
    for (int i = 0; i < 2 && written; ++i) {
      write_ns[i].push_back(MonotonicNowNs());
      written = writers[i]->Write(packed[i][k % packed[i].size()]);
      write_end_ns[i].push_back(MonotonicNowNs());
    }
    next += period_ns;
    const int64_t wait = next - MonotonicNowNs();
    if (wait > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // the last frames delivered
  for (auto& device : devices) device->Interrupt();
  EXPECT_TRUE(written) << writers[0]->error() << " " << writers[1]->error();

  for (int i = 0; i < 2; ++i) {
    const CameraRun run = runs[i].get();
    const V4l2Stats stats = devices[i]->stats();
    EXPECT_EQ(run.error, "");
    EXPECT_EQ(stats.device_losses, 0);
    EXPECT_GE(run.stamp_ns.size(), write_ns[i].size() * 9 / 10) << devices[i]->name();
    std::vector<double> latency_ms;
    int outside = 0;
    for (size_t j = 0; j < run.stamp_ns.size(); ++j) {
      latency_ms.push_back((run.grab_ns[j] - run.stamp_ns[j]) / 1e6);
      // The stamp falls inside one write of this camera (and so before Grab returned); the
      // driver's stamps are whole microseconds (timeval), truncated.
      const auto after =
          std::upper_bound(write_ns[i].begin(), write_ns[i].end(), run.stamp_ns[j] + 999);
      const size_t k = after - write_ns[i].begin();
      if (k == 0 || run.stamp_ns[j] > write_end_ns[i][k - 1] || run.stamp_ns[j] > run.grab_ns[j]) {
        ++outside;
      }
    }
    EXPECT_EQ(outside, 0) << devices[i]->name() << ": stamps outside the writes of their frames: "
                          << "not the write time on CLOCK_MONOTONIC";
    const double wall_s = frames / kRateHz;
    std::cout << "RIGCAL-FIGURE loopback_latency " << devices[i]->name() << " "
              << FourccText(devices[i]->negotiated().fourcc) << " " << kWidth << "x" << kHeight
              << "@" << kRateHz << "Hz: " << write_ns[i].size() << " written, "
              << run.stamp_ns.size() << " captured, " << stats.sequence_drops
              << " dropped by the driver; latency ms median " << Quantile(latency_ms, 0.5)
              << " p99 " << Quantile(latency_ms, 0.99) << " max " << Quantile(latency_ms, 1.0)
              << "; capture thread CPU " << 100.0 * run.cpu_s / wall_s << "% of a core, "
              << 1e6 * run.cpu_s / std::max<size_t>(1, run.stamp_ns.size()) << " us per frame\n";
  }
}

}  // namespace
}  // namespace rigcal::drivers
