// SPDX-License-Identifier: Apache-2.0
#pragma once
// PeriodicSchedule: deadlines of periodic jobs (publish, status, state save, status lines) on one
// clock, the wall clock of a live node or the log time of a replay. The clock starts at the
// first NextDue call: a job with period p is first due at start + p; then, with catch_up (log
// time), every p after its last deadline, so a replay that jumps ahead runs it once per period
// and a published history keeps its full rate; without (wall clock), p after it last ran.
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
      for (Job& j : jobs_) j.next_ns = j.period_ns > 0 ? now_ns + j.period_ns : kNever;
    }
    int best = -1;
    for (size_t i = 0; i < jobs_.size(); ++i) {
      if (jobs_[i].next_ns <= now_ns && (best < 0 || jobs_[i].next_ns < jobs_[best].next_ns)) {
        best = static_cast<int>(i);
      }
    }
    if (best < 0) return false;
    Job& j = jobs_[static_cast<size_t>(best)];
    *job = best;
    *deadline_ns = j.next_ns;
    j.next_ns = catch_up_ ? j.next_ns + j.period_ns : now_ns + j.period_ns;
    return true;
  }

 private:
  static constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
  struct Job {
    int64_t period_ns;
    int64_t next_ns;
  };
  bool catch_up_;
  bool started_ = false;
  std::vector<Job> jobs_;
};

}  // namespace rigcal::pipeline
