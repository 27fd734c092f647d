// SPDX-License-Identifier: Apache-2.0
// Timing of the batch rig calibrator against OpenCV's hand-eye calibration.
//
//   BM_RigcalLinear/K/N             CalibrateRig, Method::kLinear, K motions per slave, N slaves
//   BM_RigcalNonlinear/K/N/cov      Method::kNonlinear, compute_covariance = cov
//   BM_OpenCvHandEye/K/method       cv::calibrateHandEye on K poses of one slave (0 TSAI, 1 PARK)
//
// Data: a GenerateDrive rig drive of K + step frames with N slaves, pairs kRelative with
// step = max(5, K / 20) frames, i.e. exactly K motions per slave whose rotation (~10-50 deg)
// stays above the general model's alpha threshold at every K (the drive's period scales with
// its length). OpenCV gets the first K absolute poses of the master and the first slave.
//
// OpenCV forms all K (K - 1) / 2 pairs of its K poses (one cv::Mat per pair and a dense 3 x
// K^2/2 system): at K = 10 000 that is 5e7 pairs, > 20 GB, so those cases report an error
// instead of running.
//
// The rigcal cases carry counters `ocv_tsai_ms` (N x OpenCV TSAI CPU time at the same K, i.e.
// one OpenCV run per slave) and `x_tsai` = rigcal CPU time / that; a summary table (CPU times)
// is printed at exit.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <tuple>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"
#include "support/opencv_handeye.h"

namespace rigcal {
namespace {

constexpr int kMaxOpenCvPoses = 2000;  // beyond: O(K^2) memory, not run

int StepFor(int motions) { return std::max(5, motions / 20); }

// Up to four slaves: the demo rig's left and rear cameras, then a right and an upward camera.
std::vector<Similarity> BenchRig(int num_slaves) {
  std::vector<Similarity> rigs = DemoRig();
  Similarity right;
  right.q = AxisAngle(Eigen::Vector3d::UnitY(), 90.0 * kRadPerDeg);
  right.C = Eigen::Vector3d(0.85, 0.05, -0.6);
  right.scale = 0.8;
  Similarity up;
  up.q = AxisAngle(Eigen::Vector3d::UnitX(), -90.0 * kRadPerDeg);
  up.C = Eigen::Vector3d(0.0, -0.4, -1.0);
  up.scale = 1.3;
  rigs.push_back(right);
  rigs.push_back(up);
  rigs.resize(static_cast<size_t>(num_slaves));
  return rigs;
}

// Drives are cached: each benchmark function is called several times by the framework.
const SyntheticDrive& Drive(int motions, int num_slaves) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::unique_ptr<SyntheticDrive>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& entry = cache[{motions, num_slaves}];
  if (!entry) {
    std::vector<std::string> names = {"cam0"};
    for (int i = 1; i <= num_slaves; ++i) names.push_back("cam" + std::to_string(i));
    DriveOptions options;
    options.num_frames = motions + StepFor(motions);
    options.seed = 42;
    entry = std::make_unique<SyntheticDrive>(GenerateDrive(names, BenchRig(num_slaves), options));
  }
  return *entry;
}

CalibrationOptions Options(int motions, Method method, bool covariance) {
  CalibrationOptions options;
  options.method = method;
  options.compute_covariance = covariance;
  options.pairs.policy = PairOptions::Policy::kRelative;
  options.pairs.step = StepFor(motions);
  return options;
}

void OpenCvPoses(int num_poses, std::vector<Pose>* master, std::vector<Pose>* slave) {
  const RigRecording& rec = Drive(num_poses, 1).recording;
  master->assign(rec.master.poses.begin(), rec.master.poses.begin() + num_poses);
  slave->assign(rec.slaves[0].poses.begin(), rec.slaves[0].poses.begin() + num_poses);
}

// Process CPU time: the ratios stay meaningful on a loaded machine (both solvers are
// single-threaded here: Ceres runs with num_threads = 1, OpenCV's hand-eye code is serial).
double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// OpenCV TSAI seconds for K poses (median of 3 runs below K = 1000, one run above), cached.
double OpenCvTsaiSeconds(int num_poses) {
  static std::mutex mutex;
  static std::map<int, double> cache;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = cache.find(num_poses); it != cache.end()) return it->second;
  }
  if (num_poses > kMaxOpenCvPoses) return 0.0;
  std::vector<Pose> master, slave;
  OpenCvPoses(num_poses, &master, &slave);
  std::vector<double> times;
  const int runs = num_poses < 1000 ? 3 : 1;
  for (int r = 0; r < runs; ++r) {
    const double start = CpuSeconds();
    benchmark::DoNotOptimize(support::OpenCvHandEye(master, slave, support::HandEyeMethod::kTsai));
    times.push_back(CpuSeconds() - start);
  }
  std::sort(times.begin(), times.end());
  std::lock_guard<std::mutex> lock(mutex);
  return cache[num_poses] = times[times.size() / 2];
}

// Summary printed at exit: one row per rigcal case.
struct Summary {
  std::mutex mutex;
  std::map<std::tuple<std::string, int, int>, std::pair<double, double>> rows;  // ms, ocv ms
  ~Summary() {
    if (rows.empty()) return;
    std::printf(
        "\nrigcal vs OpenCV TSAI, CPU time per call (N OpenCV runs, one per slave, same K)\n");
    std::printf("%-22s %7s %3s %12s %14s %10s\n", "case", "K", "N", "rigcal ms", "OpenCV ms",
                "ratio");
    for (const auto& [key, value] : rows) {
      const auto& [name, k, n] = key;
      if (value.second > 0.0) {
        std::printf("%-22s %7d %3d %12.3f %14.3f %10.4f\n", name.c_str(), k, n, value.first,
                    value.second, value.first / value.second);
      } else {
        std::printf("%-22s %7d %3d %12.3f %14s %10s\n", name.c_str(), k, n, value.first,
                    "(not run)", "-");
      }
    }
  }
};
Summary& TheSummary() {
  static Summary summary;
  return summary;
}

void RunRigcal(benchmark::State& state, const std::string& name, Method method, bool cov) {
  const int motions = static_cast<int>(state.range(0));
  const int num_slaves = static_cast<int>(state.range(1));
  const SyntheticDrive& drive = Drive(motions, num_slaves);
  const CalibrationOptions options = Options(motions, method, cov);
  const double ocv_seconds = num_slaves * OpenCvTsaiSeconds(motions);

  // Fail loudly instead of timing an early exit.
  const RigCalibration check = CalibrateRig(drive.recording, options);
  for (const SlaveCalibration& s : check.slaves) {
    if (!s.usable()) {
      state.SkipWithError((s.name + ": " + ToString(s.termination) + ": " + s.message).c_str());
      return;
    }
  }

  const double start = CpuSeconds();
  for (auto _ : state) {
    RigCalibration result = CalibrateRig(drive.recording, options);
    benchmark::DoNotOptimize(result);
  }
  const double per_call = (CpuSeconds() - start) / static_cast<double>(state.iterations());
  state.counters["motions"] = motions;
  state.counters["slaves"] = num_slaves;
  if (ocv_seconds > 0.0) {
    state.counters["ocv_tsai_ms"] = ocv_seconds * 1e3;
    state.counters["x_tsai"] = per_call / ocv_seconds;
  }
  std::lock_guard<std::mutex> lock(TheSummary().mutex);
  TheSummary().rows[{name, motions, num_slaves}] = {per_call * 1e3, ocv_seconds * 1e3};
}

void BM_RigcalLinear(benchmark::State& state) {
  RunRigcal(state, "linear", Method::kLinear, false);
}

void BM_RigcalNonlinear(benchmark::State& state) {
  const bool cov = state.range(2) != 0;
  RunRigcal(state, cov ? "nonlinear+covariance" : "nonlinear", Method::kNonlinear, cov);
}

void BM_OpenCvHandEye(benchmark::State& state) {
  const int num_poses = static_cast<int>(state.range(0));
  const auto method =
      state.range(1) == 0 ? support::HandEyeMethod::kTsai : support::HandEyeMethod::kPark;
  state.SetLabel(support::ToString(method));
  if (num_poses > kMaxOpenCvPoses) {
    state.SkipWithError(
        "not run: OpenCV builds all K(K-1)/2 pose pairs (5e7 at K = 10000, "
        "> 20 GB)");
    return;
  }
  std::vector<Pose> master, slave;
  OpenCvPoses(num_poses, &master, &slave);
  for (auto _ : state) {
    auto result = support::OpenCvHandEye(master, slave, method);
    benchmark::DoNotOptimize(result);
  }
  state.counters["poses"] = num_poses;
  state.counters["pairs"] = 0.5 * num_poses * (num_poses - 1);
}

void RigcalArgs(benchmark::internal::Benchmark* b) {
  for (int k : {100, 1000, 10000}) {
    for (int n = 1; n <= 4; ++n) b->Args({k, n});
  }
}

void RigcalNonlinearArgs(benchmark::internal::Benchmark* b) {
  for (int cov : {0, 1}) {
    for (int k : {100, 1000, 10000}) {
      for (int n = 1; n <= 4; ++n) b->Args({k, n, cov});
    }
  }
}

BENCHMARK(BM_RigcalLinear)->Apply(RigcalArgs)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RigcalNonlinear)->Apply(RigcalNonlinearArgs)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OpenCvHandEye)
    ->ArgsProduct({{100, 1000, 10000}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace rigcal
