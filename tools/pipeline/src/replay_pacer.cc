// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/replay_pacer.h"

#include <algorithm>
#include <limits>

namespace rigcal::pipeline {
namespace {

constexpr int64_t kMinCapNs = 1'000'000'000;  // 1 s of log time
constexpr int64_t kCapAdvances = 20;          // x the log's normal advance

// b - a, saturated (stamps may be anywhere in [0, INT64_MAX]).
int64_t Gap(int64_t a, int64_t b) {
  int64_t out = 0;
  if (!__builtin_sub_overflow(b, a, &out)) return out;
  return b > a ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
}

}  // namespace

int64_t ReplayPacer::CapNs() const {
  const int n = std::min(advance_count_, kAdvances);
  if (n < 4) return kMinCapNs;
  std::array<int64_t, kAdvances> sorted = advances_;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.begin() + n);
  const int64_t normal = sorted[static_cast<size_t>(n / 2)];
  return std::max(kMinCapNs, normal > kMinCapNs / kCapAdvances ? kCapAdvances * normal : 0);
}

ReplayPacer::Step ReplayPacer::Observe(int camera, int64_t t_ns, Clock::time_point now) {
  if (clock_ns_ < 0) {
    Follow(t_ns, now);
    return Step::kFirst;
  }
  const int64_t gap = Gap(clock_ns_, t_ns);
  last_gap_ns_ = gap;
  const int64_t cap = CapNs();
  if (gap >= -cap && gap <= cap) {
    run_ = 0;  // an event on the clock's timeline ends any run
    if (gap > 0) {
      advances_[static_cast<size_t>(advance_count_ % kAdvances)] = gap;
      if (++advance_count_ >= 2 * kAdvances) advance_count_ -= kAdvances;
      clock_ns_ = t_ns;
    }
    return Step::kOnTime;
  }
  if (ContinuesRun(camera, t_ns)) {
    ++run_;
    run_two_cameras_ = run_two_cameras_ || camera != run_camera_;
    run_last_ns_ = t_ns;
  } else {
    StartRun(camera, t_ns);
  }
  if ((run_two_cameras_ && run_ >= kConfirmEvents) || run_ >= kLoneEvents) {
    run_ = 0;
    ++new_timelines_;
    Follow(t_ns, now);
    return Step::kNewTime;
  }
  if (gap < 0) return Step::kBehind;
  ++glitches_;
  return Step::kGlitch;
}

bool ReplayPacer::ContinuesRun(int camera, int64_t t_ns) const {
  if (run_ == 0) return false;
  // One camera alone: its stamps advance; with another camera: within the cap of each other.
  const int64_t gap = Gap(run_last_ns_, t_ns);
  if (camera == run_camera_ && !run_two_cameras_) return gap > 0 && gap <= CapNs();
  return gap >= -CapNs() && gap <= CapNs();
}

void ReplayPacer::StartRun(int camera, int64_t t_ns) {
  run_ = 1;
  run_last_ns_ = t_ns;
  run_camera_ = camera;
  run_two_cameras_ = false;
}

void ReplayPacer::Follow(int64_t t_ns, Clock::time_point now) {
  clock_ns_ = t_ns;
  origin_ns_ = t_ns;
  origin_wall_ = now;
}

ReplayPacer::Clock::time_point ReplayPacer::Due(double speed) const {
  if (clock_ns_ < 0 || !(speed > 0.0)) return origin_wall_;
  // clock_ns_ - origin_ns_ is the sum of advances of at most the cap each: finite, >= 0.
  const double wait_s = static_cast<double>(clock_ns_ - origin_ns_) * 1e-9 / speed;
  return origin_wall_ +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait_s));
}

}  // namespace rigcal::pipeline
