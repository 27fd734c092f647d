// SPDX-License-Identifier: Apache-2.0
#pragma once
// ReplayPacer: the log time of a replay, kept from glitched stamps, and how long `--speed`
// waits for an event. The pacer's clock follows the log's stamps while they advance by at most
// the cap (max(1 s, 20 x the log's normal advance: the median of its last 16 advances)). A stamp
// further from the clock, ahead (a glitch, e.g. INT64_MAX) or behind (a camera's events seconds
// late in the file, as `record --fast` writes them, or a restart of the clock), is not waited
// for and moves nothing; it is followed as a new timeline only when confirmed:
// stamps of at least two cameras on it (each within the cap of the run's newest), or
// kLoneEvents of one camera with no event of another camera in between. A stamp behind the
// clock within the cap (another camera's earlier frame) needs no wait. So no single wait is
// longer than the cap / speed, and a few glitched stamps neither stall nor skip the pacing.
//
// Not thread-safe: the replay's reader thread owns it.

#include <array>
#include <chrono>
#include <cstdint>
#include <string>

namespace rigcal::pipeline {

class ReplayPacer {
 public:
  using Clock = std::chrono::steady_clock;

  // What Observe made of a stamp.
  enum class Step {
    kFirst,    // the first stamp: the clock's origin
    kOnTime,   // within the cap of the clock (moved it when ahead)
    kBehind,   // further behind the clock than the cap (a camera's events late in the file),
               // not (yet) a new timeline: needs no wait, moved nothing
    kGlitch,   // further ahead than the cap, not (yet) a new timeline: moved nothing
    kNewTime,  // confirmed a new timeline: the clock jumped to it
  };

  // Takes the stamp `t_ns` of an event of `camera` read at wall time `now`.
  Step Observe(int camera, int64_t t_ns, Clock::time_point now);

  // The log time: the newest stamp the clock followed (-1 before the first).
  int64_t now_ns() const { return clock_ns_; }
  // When the clock's time is due at `speed` x real time (> 0): a wall time at most the cap /
  // speed after the last Observe.
  Clock::time_point Due(double speed) const;
  // The largest advance of the clock followed without a confirmation [ns].
  int64_t CapNs() const;
  // Stamps ahead taken as glitches so far, and new timelines followed.
  uint64_t glitches() const { return glitches_; }
  uint64_t new_timelines() const { return new_timelines_; }
  // The last step's gap from the clock [ns] (kGlitch / kNewTime: how far the stamp was).
  int64_t last_gap_ns() const { return last_gap_ns_; }

  // Events of one camera alone that confirm a new timeline.
  static constexpr int kLoneEvents = 40;
  // Events of at least two cameras that confirm one.
  static constexpr int kConfirmEvents = 4;

 private:
  static constexpr int kAdvances = 16;
  bool ContinuesRun(int camera, int64_t t_ns) const;
  void StartRun(int camera, int64_t t_ns);
  void Follow(int64_t t_ns, Clock::time_point now);

  int64_t clock_ns_ = -1;
  int64_t origin_ns_ = 0;  // the log time at origin_wall_ (since the last new timeline)
  Clock::time_point origin_wall_;
  std::array<int64_t, kAdvances> advances_{};
  int advance_count_ = 0;
  // The run of stamps far from the clock: its newest stamp, length, first camera and whether a
  // second camera joined it.
  int run_ = 0;
  int64_t run_last_ns_ = 0;
  int run_camera_ = -1;
  bool run_two_cameras_ = false;
  uint64_t glitches_ = 0;
  uint64_t new_timelines_ = 0;
  int64_t last_gap_ns_ = 0;
};

}  // namespace rigcal::pipeline
