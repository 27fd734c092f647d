// SPDX-License-Identifier: Apache-2.0
#pragma once
// Scheduler: the timing of the trigger lines, as compare values programmed ahead into the
// board's timer channels (LineTimers). Pure logic on a µs time base, so it runs unchanged on the
// host (tests, the simulated trigger).
//
// Tick k of a run started at t_start has the nominal time T_k = t0 + floor(k * 1e9 / rate_mhz)
// µs (exact tick times: no accumulated rounding for rates whose period is not a whole number of
// µs), where t0 = t_start + kArmLeadUs + lead and lead = max(0, max over enabled lines of
// -RiseOffsetUs()). Line L rises at T_k + RiseOffsetUs(L) = T_k + phase_offset - exposure / 2 and
// falls width later.
//
// Edges: every line has one edge armed in its compare channel at a time. The hardware makes the
// edge at its compare time; OnCompare (the compare interrupt) then arms the line's next edge:
// the fall after a rise, the next tick's rise after a fall. The main loop never sets a level, so
// an edge's time does not depend on it. A fall that cannot be armed in time (the interrupt was
// held off for longer than the width) is driven at once and counted late; a rise that cannot be
// armed in time is not made: the line skips to the first tick whose rise lies at least
// kArmLeadUs ahead, and the ticks it skipped are skipped for every line (never reported: the
// host sees the gap; heartbeat skipped_ticks). Ticks whose rises were all made are reported.
//
// Reports: when the last enabled line has risen for tick k, the compare context queues the
// report of tick k {seq = first_seq + k, T_k}; the main loop sends it once its clock has reached
// T_k (PopReport), so a report never leaves before T_k nor before any rise of its tick. T_k is
// the compare times' own reference: what the report states is what the hardware did.
//
// Contexts: Configure, Start, Stop, PopReport, NextReportUs in the main loop; OnCompare in the
// compare context (an interrupt, or the main loop with it masked); LastRise in the capture
// context, which the compare context may preempt (it reads until consistent). Start arms
// the first edges only after the run's state is set; Stop releases every line before it reads
// the state. The counters are atomics (the main loop reads them for heartbeats).
//
// No heap, no exceptions; one instance per generator.

#include <atomic>
#include <cstdint>

#include "rigcal/trigger_core/line_timers.h"
#include "rigcal/trigger_core/spsc_ring.h"
#include "rigcal/trigger_core/trigger_config.h"
#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger_core {

class Scheduler {
 public:
  // The first rise of a run lies at least this far after Start: time to arm every line.
  static constexpr uint32_t kArmLeadUs = 1'000;
  static constexpr uint32_t kReportQueue = 16;

  // Sets the configuration for the next Start. Call while stopped; `config` must pass
  // CheckConfig (the command handler checks it). Returns false (and changes nothing) otherwise.
  bool Configure(const TriggerConfig& config);
  // Starts ticking (see the class comment) and arms every enabled line's first rise; false when
  // running already or no line is enabled. Sequence numbers continue from the last run.
  bool Start(uint64_t now_us, LineTimers* timers);
  // Stops at once: every line released (low, nothing armed). Reports already queued stay queued.
  void Stop(LineTimers* timers);
  bool running() const { return running_.load(std::memory_order_acquire); }

  // Compare context: the armed edge of `line` has happened. Arms its next edge.
  void OnCompare(int line, LineTimers* timers);
  // Compare context: the tick (seq) and time of `line`'s last rise; false before its first.
  bool LastRise(int line, uint32_t* seq, uint64_t* rise_us) const;
  // The time `line`'s next rise is armed for or will be (compare context).
  uint64_t NextRiseUs(int line) const;

  // Main loop: the next queued report if its T_k <= now_us (removed); false otherwise.
  bool PopReport(uint64_t now_us, proto::PulseReport* report);
  // Main loop: T_k of the next queued report (UINT64_MAX when none is queued).
  uint64_t NextReportUs() const;

  uint32_t next_seq() const { return next_seq_.load(std::memory_order_acquire); }
  uint32_t late_edges() const { return late_edges_.load(std::memory_order_relaxed); }
  uint32_t skipped_ticks() const { return skipped_ticks_.load(std::memory_order_relaxed); }
  uint32_t dropped_reports() const { return dropped_reports_.load(std::memory_order_relaxed); }
  const TriggerConfig& config() const { return config_; }
  // Nominal time of tick k of the current run, µs.
  uint64_t TickTimeUs(uint64_t k) const { return t0_ + (k * 1'000'000'000ull) / config_.rate_mhz; }

 private:
  // The tick clock of a line: tick k, T_k, and (k * 1e9) mod rate (T_k's fraction of a µs in
  // units of 1/rate), so the next tick needs no division.
  struct TickClock {
    uint64_t k = 0;
    uint64_t t_us = 0;
    uint32_t frac = 0;
  };
  struct LineState {
    TickClock tick;         // the tick of the armed (or next) rise
    bool high = false;      // the armed edge is the fall
    uint64_t armed_us = 0;  // time of the armed edge
    uint64_t rises = 0;     // ticks up to which this line has risen (last risen tick + 1)
    uint64_t last_rise_us = 0;
  };
  void Advance(TickClock* clock) const;
  TickClock ClockAt(uint64_t k) const;
  uint64_t RiseUs(int line, const TickClock& clock) const;
  // Arms line's rise at its tick clock, skipping ticks whose rise cannot be armed in time.
  void ArmRise(int line, LineTimers* timers);
  void QueueReports();
  // Ticks [from_k, before_k) are skipped by every line (merged with a range not yet passed).
  void Skip(uint64_t from_k, uint64_t before_k);

  TriggerConfig config_;
  uint32_t period_us_ = 0;    // 1e9 / rate, whole µs (Start)
  uint32_t period_rem_ = 0;   // 1e9 mod rate: the fraction, in 1/rate µs
  std::atomic<bool> running_{false};
  uint8_t enabled_mask_ = 0;
  uint64_t t0_ = 0;
  uint32_t first_seq_ = 0;  // seq of tick 0 of this run
  LineState lines_[proto::kMaxLines];
  TickClock report_;          // the next tick to report
  uint64_t skip_from_k_ = 0;  // ticks [skip_from_k_, skip_before_k_) are skipped by every line
  uint64_t skip_before_k_ = 0;
  SpscRing<proto::PulseReport, kReportQueue> reports_;
  std::atomic<uint32_t> next_seq_{0};  // seq the next reported tick gets
  std::atomic<uint32_t> late_edges_{0};
  std::atomic<uint32_t> skipped_ticks_{0};
  std::atomic<uint32_t> dropped_reports_{0};
};

}  // namespace rigcal::trigger_core
