// SPDX-License-Identifier: Apache-2.0
// Cost of the online estimator (issue "Online": targets in the README).
//
//   BM_EstimatorUpdate/K/N     RigEstimator::AddSet after K sets already consumed, N slaves;
//                              counter us_per_set_slave = CPU per matched set per slave (must be
//                              flat in K: the statistics have a fixed size).
//   BM_WindowRefinement/W      RefineWindow (Ceres, background thread's job) on a W-motion window.
//   BM_OpenCvRerun/K           what a naive online calibrator would do at each new set: re-run
//                              cv::calibrateHandEye (TSAI) on the K accumulated poses; counter
//                              x_update = that / one estimator update of one slave.
//   BM_EstimatorMemory/S       S sets (one iteration); counters rss_mb_before / rss_mb_after /
//                              rss_growth_mb of the whole process.
//
// Data: GenerateDrive of the demo rig (general motion, 0.05 deg / 2 mm pose noise, 20 Hz).
// A drive is replayed cyclically with time offsets when more sets are needed than it has.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/lcm/process_stats.h"
#include "support/opencv_handeye.h"

namespace rigcal {
namespace {

constexpr int kDriveFrames = 20'000;

const SyntheticDrive& Drive(int num_slaves) {
  static std::mutex mutex;
  static std::map<int, SyntheticDrive> drives;
  std::lock_guard<std::mutex> lock(mutex);
  auto it = drives.find(num_slaves);
  if (it == drives.end()) {
    std::vector<std::string> names = {"front", "left", "back", "right", "up"};
    names.resize(static_cast<size_t>(num_slaves) + 1);
    std::vector<Similarity> rigs = DemoRig();
    Similarity right = rigs[0];
    right.C.x() = -right.C.x();
    rigs.push_back(right);
    Similarity up = rigs[1];
    up.C.y() = -0.4;
    rigs.push_back(up);
    rigs.resize(static_cast<size_t>(num_slaves));
    DriveOptions d;
    d.num_frames = kDriveFrames;
    it = drives.emplace(num_slaves, GenerateDrive(names, rigs, d)).first;
  }
  return it->second;
}

std::vector<std::string> Names(const RigRecording& rec) {
  std::vector<std::string> names = {rec.master.name};
  for (const CameraTrack& s : rec.slaves) names.push_back(s.name);
  return names;
}

// Feeds set number `n` (cyclic over the drive, time shifted per cycle).
class SetFeeder {
 public:
  explicit SetFeeder(const RigRecording& rec)
      : rec_(rec),
        poses_(rec.slaves.size() + 1),
        period_ns_(rec.t_ns.back() - rec.t_ns[0] + (rec.t_ns[1] - rec.t_ns[0])) {}
  void Feed(RigEstimator* estimator, int64_t n) {
    const size_t k = static_cast<size_t>(n % static_cast<int64_t>(rec_.size()));
    const int64_t t = rec_.t_ns[k] + (n / static_cast<int64_t>(rec_.size())) * period_ns_;
    for (size_t cam = 0; cam < poses_.size(); ++cam) {
      CameraPose p;
      p.camera = static_cast<int>(cam);
      p.t_ns = t;
      p.pose = cam == 0 ? rec_.master.poses[k] : rec_.slaves[cam - 1].poses[k];
      poses_[cam] = p;
    }
    estimator->AddSet(t, poses_);
  }

 private:
  const RigRecording& rec_;
  std::vector<std::optional<CameraPose>> poses_;
  int64_t period_ns_;
};

void BM_EstimatorUpdate(benchmark::State& state) {
  const int64_t warm = state.range(0);
  const int slaves = static_cast<int>(state.range(1));
  const RigRecording& rec = Drive(slaves).recording;
  RigEstimatorOptions options;
  RigEstimator estimator(Names(rec), options);
  SetFeeder feeder(rec);
  int64_t n = 0;
  for (; n < warm; ++n) feeder.Feed(&estimator, n);
  for (auto _ : state) feeder.Feed(&estimator, n++);
  // Seconds per matched set per slave (shown with an SI prefix, e.g. 540n = 0.54 us).
  state.counters["per_set_slave"] = benchmark::Counter(
      slaves, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["motions"] = estimator.Estimate().rig.slaves[0].motions.used;
}

void BM_WindowRefinement(benchmark::State& state) {
  const int window = static_cast<int>(state.range(0));
  const RigRecording& rec = Drive(1).recording;
  RigEstimatorOptions options;
  options.window_size = window;
  RigEstimator estimator(Names(rec), options);
  SetFeeder feeder(rec);
  for (int64_t n = 0; n < static_cast<int64_t>(rec.size()); ++n) feeder.Feed(&estimator, n);
  const RefinementJob job = estimator.MakeRefinementJob(0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(RefineWindow(job));
  }
  state.counters["window_motions"] = static_cast<double>(job.motions.size());
}

std::atomic<double> g_update_us_one_slave{0.0};

void BM_OpenCvRerun(benchmark::State& state) {
  const size_t k = static_cast<size_t>(state.range(0));
  const RigRecording& rec = Drive(1).recording;
  const std::vector<Pose> master(rec.master.poses.begin(), rec.master.poses.begin() + k);
  std::vector<Pose> slave(rec.slaves[0].poses.begin(), rec.slaves[0].poses.begin() + k);
  for (Pose& p : slave) p.C *= DemoRig()[0].scale;  // OpenCV needs one metric
  const double opencv_start = lcm::ProcessCpuSeconds();
  for (auto _ : state) {
    benchmark::DoNotOptimize(support::OpenCvHandEye(master, slave, support::HandEyeMethod::kTsai));
  }
  const double opencv_s =
      (lcm::ProcessCpuSeconds() - opencv_start) / static_cast<double>(state.iterations());
  // One update of one slave, measured here (the two benchmarks may run in any order).
  RigEstimator estimator(Names(rec), RigEstimatorOptions());
  SetFeeder feeder(rec);
  for (int64_t n = 0; n < 2000; ++n) feeder.Feed(&estimator, n);
  const double start = lcm::ProcessCpuSeconds();
  constexpr int kUpdates = 4000;
  for (int64_t n = 2000; n < 2000 + kUpdates; ++n) feeder.Feed(&estimator, n);
  const double update_s = (lcm::ProcessCpuSeconds() - start) / kUpdates;
  state.counters["update_us"] = 1e6 * update_s;
  state.counters["x_update"] = opencv_s / update_s;
}

void BM_EstimatorMemory(benchmark::State& state) {
  const int64_t sets = state.range(0);
  const RigRecording& rec = Drive(2).recording;
  for (auto _ : state) {
    RigEstimator estimator(Names(rec), RigEstimatorOptions());
    SetFeeder feeder(rec);
    for (int64_t n = 0; n < 20'000; ++n) feeder.Feed(&estimator, n);  // reach steady state
    const double before = static_cast<double>(lcm::ResidentSetBytes()) / (1 << 20);
    for (int64_t n = 20'000; n < sets; ++n) feeder.Feed(&estimator, n);
    const double after = static_cast<double>(lcm::ResidentSetBytes()) / (1 << 20);
    state.counters["rss_mb_before"] = before;
    state.counters["rss_mb_after"] = after;
    state.counters["rss_growth_mb"] = after - before;
    state.counters["motions"] = estimator.Estimate().rig.slaves[0].motions.used;
  }
}

BENCHMARK(BM_EstimatorUpdate)
    ->ArgsProduct({{1'000, 10'000, 100'000}, {1, 2, 4}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WindowRefinement)->Arg(100)->Arg(400)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenCvRerun)->Arg(500)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EstimatorMemory)->Arg(1'000'000)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace
}  // namespace rigcal
