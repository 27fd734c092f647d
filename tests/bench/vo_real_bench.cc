// SPDX-License-Identifier: Apache-2.0
// Speed of the monocular VO per real 640x480 frame on one core (issue 34 §7: median <= 4 ms,
// p90 <= 6 ms). The sequences of ../shared/data/real_mono (support/real_mono_sequence.h) are
// loaded once; every benchmark iteration runs the VO over a whole sequence (a new VO each
// time, so every run sees the same frames in the same state). Times are the CPU time of the
// VO's thread per frame (OpenCV limited to one thread), so the figures hold on a busy machine
// too; `median_ms` and `p90_ms` are over all frames of all runs (initialising, tracking,
// keyframes), `keyframes` the fraction of frames that became keyframes. Skipped (with an error
// line) when a sequence is missing.
//
//   build/tests/bench/rigcal_calib_bench --benchmark_filter=MonocularVoReal

#include <benchmark/benchmark.h>

#include <algorithm>
#include <ctime>
#include <map>
#include <opencv2/core/utility.hpp>
#include <string>

#include "rigcal/vo/monocular_vo.h"
#include "support/real_mono_sequence.h"

namespace {

using rigcal::support::RealMonoSequence;
using rigcal::vo::MonocularVo;

double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return 1e3 * static_cast<double>(ts.tv_sec) + 1e-6 * static_cast<double>(ts.tv_nsec);
}

// The sequence `name`, loaded on first use; null when missing.
const RealMonoSequence* Sequence(const std::string& name) {
  static std::map<std::string, std::unique_ptr<RealMonoSequence>> loaded;
  auto it = loaded.find(name);
  if (it == loaded.end()) {
    std::unique_ptr<RealMonoSequence> s;
    if (rigcal::support::RealMonoAvailable(name)) {
      auto sequence = rigcal::support::LoadRealMono(name);
      if (sequence.ok()) s = std::make_unique<RealMonoSequence>(std::move(*sequence));
    }
    it = loaded.emplace(name, std::move(s)).first;
  }
  return it->second.get();
}

double Quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

void BM_MonocularVoReal(benchmark::State& state, const std::string& name) {
  const RealMonoSequence* s = Sequence(name);
  if (s == nullptr) {
    state.SkipWithError(("no " + rigcal::support::RealMonoFolder(name)).c_str());
    return;
  }
  const int opencv_threads = cv::getNumThreads();
  cv::setNumThreads(1);  // one core, as on the vehicle computer
  std::vector<double> cpu_ms;
  int keyframes = 0;
  for (auto _ : state) {
    MonocularVo vo(s->camera, 0);
    double run_ms = 0.0;
    for (size_t k = 0; k < s->grey.size(); ++k) {
      const double start_ms = ThreadCpuMs();
      const auto result = vo.Process(s->t_ns[k], s->grey[k]);
      const double ms = ThreadCpuMs() - start_ms;
      cpu_ms.push_back(ms);
      run_ms += ms;
      keyframes += result.keyframe;
      benchmark::DoNotOptimize(result);
    }
    state.SetIterationTime(1e-3 * run_ms);
  }
  cv::setNumThreads(opencv_threads);
  state.counters["median_ms"] = Quantile(cpu_ms, 0.5);
  state.counters["p90_ms"] = Quantile(cpu_ms, 0.9);
  state.counters["keyframes"] = static_cast<double>(keyframes) / static_cast<double>(cpu_ms.size());
  state.counters["frames"] = static_cast<double>(s->grey.size());
}
BENCHMARK_CAPTURE(BM_MonocularVoReal, visp_rbt_sequence, std::string("visp_rbt_sequence"))
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(10);
BENCHMARK_CAPTURE(BM_MonocularVoReal, visp_mbt_cube, std::string("visp_mbt_cube"))
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond)
    ->Iterations(10);

}  // namespace
