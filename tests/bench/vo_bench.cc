// SPDX-License-Identifier: Apache-2.0
// Speed of the monocular VO per 752x480 frame on one core (issue 4: <= 4 ms median).
// A 60-degree pinhole camera moves through the textured room of the VO tests, rendered by the
// simulated rig (support/room_sequence.h); every benchmark iteration processes one frame (frames
// are rendered once, before timing). Times are
// the CPU time of the VO's thread (OpenCV limited to one thread), so the figure holds on a busy
// machine too; `median_ms` is the median over the frames processed while tracking, `p90_ms`
// the 90th percentile, `median_wall_ms` the median wall-clock time, `keyframes` the fraction
// of frames that became keyframes (these run the local bundle adjustment).
//
//   build-vo/tests/bench/rigcal_calib_bench --benchmark_filter=MonocularVo

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <opencv2/core/utility.hpp>

#include "rigcal/vo/monocular_vo.h"
#include "support/ideal_cameras.h"
#include "support/room_sequence.h"

namespace {

using rigcal::vo::MonocularVo;
using rigcal::vo::VoState;

struct Frames {
  std::shared_ptr<const rigcal::camera::CameraModel> camera =
      rigcal::support::PinholeWithFov(752, 480, 60.0);
  std::vector<cv::Mat> images;
  Frames() {
    constexpr int kFrames = 200;
    std::vector<rigcal::Pose> poses;
    for (int k = 0; k < kFrames; ++k) poses.push_back(rigcal::support::RoomPose(k));
    const rigcal::sim::SimulatedRig rig = rigcal::support::MakeRoomSequence(camera, poses).value();
    for (int k = 0; k < kFrames; ++k) images.push_back(rig.RenderFrame(0, k));
  }
};

// CPU time of the calling thread: the VO's cost on its core, whatever else the machine runs.
double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

const Frames& SharedFrames() {
  static const Frames frames;
  return frames;
}

void BM_MonocularVoFrame752x480(benchmark::State& state) {
  const Frames& frames = SharedFrames();
  // One core: OpenCV's internal parallel loops (KLT, pyramids) would use a thread pool.
  const int opencv_threads = cv::getNumThreads();
  cv::setNumThreads(1);
  auto vo = std::make_unique<MonocularVo>(frames.camera, 0);
  size_t next = 0;
  std::vector<double> ms, wall_ms;
  int keyframes = 0;
  for (auto _ : state) {
    if (next == frames.images.size()) {  // restart the sequence (not timed)
      state.PauseTiming();
      vo = std::make_unique<MonocularVo>(frames.camera, 0);
      next = 0;
      state.ResumeTiming();
    }
    const auto start = std::chrono::steady_clock::now();
    const double cpu_start = ThreadCpuSeconds();
    const auto result = vo->Process(static_cast<int64_t>(next) * 50'000'000, frames.images[next]);
    const double cpu = ThreadCpuSeconds() - cpu_start;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    state.SetIterationTime(cpu);
    if (result.state == VoState::kTracking) {
      ms.push_back(1e3 * cpu);
      wall_ms.push_back(1e3 * elapsed);
      keyframes += result.keyframe;
    }
    ++next;
    benchmark::DoNotOptimize(result);
  }
  cv::setNumThreads(opencv_threads);
  if (!ms.empty()) {
    std::sort(ms.begin(), ms.end());
    state.counters["median_ms"] = ms[ms.size() / 2];
    state.counters["p90_ms"] = ms[ms.size() * 9 / 10];
    std::sort(wall_ms.begin(), wall_ms.end());
    state.counters["median_wall_ms"] = wall_ms[wall_ms.size() / 2];
    state.counters["keyframes"] = static_cast<double>(keyframes) / ms.size();
    state.counters["tracking_frames"] = static_cast<double>(ms.size());
  }
}
BENCHMARK(BM_MonocularVoFrame752x480)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(600);

}  // namespace
