// SPDX-License-Identifier: Apache-2.0
// Figures of a long capture of two vivid devices at once (not part of `make test`: the eval test
// device/vivid_long_run_eval runs it for RIGCAL_DEVICE_RUN_S seconds, default 300):
//  - frames dropped (driver sequence gaps) per camera;
//  - capture latency: from the buffer's kernel stamp (vivid stamps when it finishes the frame)
//    to the frame leaving Grab, converted, which is when the pipeline pushes it into the
//    camera's VO queue: median, 99th percentile and maximum;
//  - CPU time of each capture thread (RUSAGE_THREAD), per frame and as a share of one core.
// Under emulation (QEMU TCG) every CPU figure is that of the emulated machine.

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <algorithm>
#include <cstdlib>
#include <future>
#include <vector>

#include "guest_skip.h"
#include "rigcal/capture/v4l2_device.h"
#include "rigcal/capture/v4l2_timestamp.h"
#include "sample_quantile.h"

namespace rigcal::capture {
namespace {

struct RunFigures {
  int64_t frames = 0;
  std::vector<double> latency_ms;
  double cpu_s = 0.0;
  double wall_s = 0.0;
};

RunFigures Capture(V4l2Device* device, double seconds) {
  RunFigures out;
  const int64_t start = MonotonicNowNs();
  const auto end = start + static_cast<int64_t>(seconds * 1e9);
  rusage before{};
  getrusage(RUSAGE_THREAD, &before);
  while (MonotonicNowNs() < end) {
    auto frame = device->Grab();
    if (!frame.ok() || !frame->has_value()) break;
    out.latency_ms.push_back((MonotonicNowNs() - (*frame)->t_ns) / 1e6);
    ++out.frames;
  }
  rusage after{};
  getrusage(RUSAGE_THREAD, &after);
  auto secs = [](const timeval& t) { return t.tv_sec + t.tv_usec / 1e6; };
  out.cpu_s =
      secs(after.ru_utime) - secs(before.ru_utime) + secs(after.ru_stime) - secs(before.ru_stime);
  out.wall_s = (MonotonicNowNs() - start) / 1e9;
  return out;
}

TEST(VividLongRun, DropsLatencyAndCpuPerCamera) {
  RIGCAL_REQUIRE_NODE("/dev/video1");
  const char* env = std::getenv("RIGCAL_DEVICE_RUN_S");
  const double seconds = env ? std::atof(env) : 300.0;
  std::vector<std::unique_ptr<V4l2Device>> devices;
  for (int i = 0; i < 2; ++i) {
    V4l2Options options;
    options.device = "bus:platform:vivid-00" + std::to_string(i);
    options.width = 640;
    options.height = 480;
    options.formats = {i == 0 ? PixelFormat::kGrey : PixelFormat::kYuyv};
    options.frame_rate_hz = 30.0;
    auto device = V4l2Device::Open("cam" + std::to_string(i), i, options);
    ASSERT_TRUE(device.ok()) << device.error();
    devices.push_back(std::move(*device));
  }
  std::vector<std::future<RunFigures>> runs;
  for (auto& device : devices) {
    runs.push_back(std::async(std::launch::async,
                              [&device, seconds] { return Capture(device.get(), seconds); }));
  }
  for (size_t i = 0; i < devices.size(); ++i) {
    const RunFigures f = runs[i].get();
    const V4l2Stats s = devices[i]->stats();
    const double expected = f.wall_s * devices[i]->frame_rate_hz();
    std::cout << "RIGCAL-FIGURE vivid cam" << i << " "
              << FourccText(devices[i]->negotiated().fourcc) << " 640x480@"
              << devices[i]->frame_rate_hz() << "Hz: " << f.wall_s << " s, " << f.frames
              << " frames (" << expected << " nominal), " << s.sequence_drops
              << " dropped by the driver (sequence gaps), " << s.error_buffers
              << " erroneous buffers, " << s.device_losses << " device losses, latency ms median "
              << SampleQuantile(f.latency_ms, 0.5) << " p99 " << SampleQuantile(f.latency_ms, 0.99)
              << " max " << SampleQuantile(f.latency_ms, 1.0) << ", capture thread CPU "
              << 100.0 * f.cpu_s / f.wall_s << "% of a core, "
              << 1e6 * f.cpu_s / std::max<int64_t>(1, f.frames) << " us per frame\n";
    EXPECT_GT(f.frames, 0);
    EXPECT_EQ(s.device_losses, 0);
  }
}

}  // namespace
}  // namespace rigcal::capture
