// SPDX-License-Identifier: Apache-2.0
#pragma once
// PeriodicSchedule: deadlines of periodic jobs (publish, status, state save, status lines) on one
// clock, the wall clock of a live node or the log time of a replay. The clock starts at the
// first NextDue call: a job with period p is first due at start + p; then, with catch_up (log
// time), every p after its last deadline, so a replay that jumps ahead runs it once per period
// and a published history keeps its full rate; without (wall clock), p after it last ran.
// Bounded work per clock value: a job runs at most kMaxCatchUp times to catch up with one jump
// of the clock (the periods before those are skipped: a gap of hours in a log, or a stamp near
// INT64_MAX, must not mean billions of publications), and deadlines saturate at INT64_MAX
// instead of overflowing.
//
// Not thread-safe: one thread owns a schedule.

#include <cstdint>
#include <limits>
#include <vector>

namespace rigcal::pipeline {

class PeriodicSchedule {
 public:
  // `catch_up`: a job due several periods ago is due once per period (log time, where every
  // period must leave its message); otherwise once (wall clock).
  explicit PeriodicSchedule(bool catch_up) : catch_up_(catch_up) {}

  // Adds a job every period_ns (<= 0: never due); returns its id.
  int Add(int64_t period_ns) {
    jobs_.push_back({period_ns, kNever});
    return static_cast<int>(jobs_.size()) - 1;
  }

  // The next due job at now_ns with its deadline, or false when none is due: call in a loop
  // until false. The first call starts the clock at now_ns.
  bool NextDue(int64_t now_ns, int* job, int64_t* deadline_ns) {
    if (!started_) {
      started_ = true;
      for (Job& j : jobs_)
        j.next_ns = j.period_ns > 0 ? SaturatingAdd(now_ns, j.period_ns) : kNever;
    }
    int best = -1;
    for (size_t i = 0; i < jobs_.size(); ++i) {
      // kNever is never due, not even at now_ns == INT64_MAX (a saturated deadline).
      if (jobs_[i].next_ns != kNever && jobs_[i].next_ns <= now_ns &&
          (best < 0 || jobs_[i].next_ns < jobs_[best].next_ns)) {
        best = static_cast<int>(i);
      }
    }
    if (best < 0) return false;
    Job& j = jobs_[static_cast<size_t>(best)];
    // More periods behind than a catch-up may run: only the last kMaxCatchUp are run.
    if (catch_up_ && (now_ns - j.next_ns) / j.period_ns >= kMaxCatchUp) {
      j.next_ns = now_ns - (kMaxCatchUp - 1) * j.period_ns;
    }
    *job = best;
    *deadline_ns = j.next_ns;
    j.next_ns = SaturatingAdd(catch_up_ ? j.next_ns : now_ns, j.period_ns);
    return true;
  }

  // The most runs of one job to catch up with one jump of the clock.
  static constexpr int64_t kMaxCatchUp = 1000;

 private:
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
  // a + b for b > 0, INT64_MAX (never) when that overflows.
  static int64_t SaturatingAdd(int64_t a, int64_t b) { return a > kNever - b ? kNever : a + b; }
  struct Job {
    int64_t period_ns;
    int64_t next_ns;
  };
  bool catch_up_;
  bool started_ = false;
  std::vector<Job> jobs_;
};

}  // namespace rigcal::pipeline
