// SPDX-License-Identifier: Apache-2.0
// Capture latency and CPU of the V4L2 source per camera, on v4l2loopback. Unlike vivid, which
// stamps a frame with its nominal schedule (up to a period ahead of its delivery), v4l2loopback
// takes its stamp when the writer writes the frame; it does not flag the stamp as
// CLOCK_MONOTONIC, so the V4L2 source stamps such frames at DQBUF (v4l2_timestamp.h). The test
// knows when every frame was written, so it measures both:
//  - write to VO queue: from the end of the writer's write() (the driver's stamp lies inside
//    it) to Grab returning the converted frame, which the pipeline's capture loop pushes into
//    the camera's VO queue at once: the driver's hand-over, poll wake-up, DQBUF, conversion to
//    grey and requeueing;
//  - DQBUF stamp to VO queue: conversion and requeueing only.
// Per camera (cam0 GREY, cam1 YUYV, 320x240 at 15 Hz): frames written, captured, dropped,
// latencies (median, p99, max) and the CPU of its capture thread (RUSAGE_THREAD). Under emulation
// (QEMU TCG) every figure is the emulated machine's. Checked: every frame's sequence number
// names a written frame and its stamp lies between the start of that write and the end of Grab;
// 90 % of the written frames arrive; no loss. Length: RIGCAL_DEVICE_LATENCY_S seconds (default
// 10).

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
#include "rigcal/capture/v4l2_device.h"
#include "rigcal/capture/v4l2_timestamp.h"
#include "sample_quantile.h"

namespace rigcal::capture {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr double kRateHz = 15.0;

struct CameraRun {
  std::vector<int64_t> stamp_ns;  // the frame's kernel stamp
  std::vector<int64_t> grab_ns;   // when Grab returned it
  std::vector<int64_t> seq;       // its sequence number
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
    out.seq.push_back((*frame)->seq);
  }
  out.cpu_s = ThreadCpuSeconds() - cpu_before;
  return out;
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
    std::vector<double> dequeue_ms, write_ms;
    int outside = 0;
    for (size_t j = 0; j < run.stamp_ns.size(); ++j) {
      // v4l2loopback numbers the frames of a device by its writes, from 0 (Frame.seq of a first
      // connection is the driver's sequence).
      const int64_t k = run.seq[j];
      if (k < 0 || k >= static_cast<int64_t>(write_ns[i].size()) ||
          run.stamp_ns[j] < write_ns[i][k] || run.stamp_ns[j] > run.grab_ns[j]) {
        ++outside;
        continue;
      }
      dequeue_ms.push_back((run.grab_ns[j] - run.stamp_ns[j]) / 1e6);
      write_ms.push_back((run.grab_ns[j] - write_end_ns[i][k]) / 1e6);
    }
    EXPECT_EQ(outside, 0) << devices[i]->name() << ": frames whose sequence names no write, or "
                          << "stamped before their write or after Grab returned";
    const double wall_s = frames / kRateHz;
    std::cout << "RIGCAL-FIGURE loopback_latency " << devices[i]->name() << " "
              << FourccText(devices[i]->negotiated().fourcc) << " " << kWidth << "x" << kHeight
              << "@" << kRateHz << "Hz: " << write_ns[i].size() << " written, "
              << run.stamp_ns.size() << " captured, " << stats.sequence_drops
              << " dropped by the driver; write to VO queue ms median "
              << SampleQuantile(write_ms, 0.5) << " p99 " << SampleQuantile(write_ms, 0.99)
              << " max " << SampleQuantile(write_ms, 1.0) << "; DQBUF stamp to VO queue ms median "
              << SampleQuantile(dequeue_ms, 0.5) << " p99 " << SampleQuantile(dequeue_ms, 0.99)
              << " max " << SampleQuantile(dequeue_ms, 1.0) << "; capture thread CPU "
              << 100.0 * run.cpu_s / wall_s << "% of a core, "
              << 1e6 * run.cpu_s / std::max<size_t>(1, run.stamp_ns.size()) << " us per frame\n";
  }
}

}  // namespace
}  // namespace rigcal::capture
