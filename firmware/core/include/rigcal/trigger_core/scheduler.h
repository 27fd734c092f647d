#pragma once
// Scheduler: the timing of the trigger lines. Pure logic on a µs time base the caller supplies
// (the board's SysTick clock, or a test's), so it runs unchanged on the host.
//
// Tick k of a run started at t_start has the nominal time T_k = t0 + floor(k * 1e9 / rate_mhz)
// µs (exact tick times: no accumulated rounding for rates whose period is not a whole number of
// µs), where t0 = t_start + lead and lead = max(0, max over enabled lines of -RiseOffsetUs()):
// the first rise is never in the past. Line L rises at T_k + RiseOffsetUs(L) =
// T_k + phase_offset - exposure / 2 and falls width later. The report of tick k (seq =
// first_seq + k) is emitted at max(T_k, last rise of the tick), never earlier than T_k.
//
// Poll(now) applies every event due at or before `now` in time order and tells the listener.
// The board calls it in its main loop as often as it can; an edge applied more than
// kLateToleranceUs after its time counts as late (on real hardware a timer output-compare would
// raise the line; the report's time is the scheduled one either way). When Poll falls more than
// one period behind (e.g. the MCU was halted), the missed ticks are skipped, not replayed: their
// sequence numbers are never reported (the host sees the gap).
//
// No heap, no exceptions; one instance per generator; not thread-safe (the board calls it from
// its main loop only).

#include <cstdint>

#include "rigcal/trigger_core/trigger_config.h"
#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger_core {

class SchedulerListener {
 public:
  // The lines' new levels (bit L = line L high), after every Poll that changed one.
  virtual void OnLines(uint8_t high_mask) = 0;
  // Tick report, in tick order.
  virtual void OnPulse(const proto::PulseReport& report) = 0;

 protected:
  ~SchedulerListener() = default;
};

class Scheduler {
 public:
  static constexpr uint32_t kLateToleranceUs = 50;

  // Sets the configuration for the next Start. Call while stopped; `config` must pass
  // CheckConfig (the command handler checks it). Returns false (and changes nothing) otherwise.
  bool Configure(const TriggerConfig& config);
  // Starts ticking at `now_us` (see the class comment); false when running already or no line
  // is enabled. Sequence numbers continue from the last run.
  bool Start(uint64_t now_us);
  // Stops at once: every line goes low (listener told), no more reports.
  void Stop(SchedulerListener* listener);
  bool running() const { return running_; }

  // Applies the events due at or before `now_us` (see the class comment).
  void Poll(uint64_t now_us, SchedulerListener* listener);
  // Time of the next event when running (UINT64_MAX when stopped): the caller may sleep until
  // then.
  uint64_t NextEventUs() const;

  uint32_t next_seq() const {
    return running_ ? first_seq_ + static_cast<uint32_t>(report_k_) : next_seq_;
  }
  uint32_t late_edges() const { return late_edges_; }
  uint32_t skipped_ticks() const { return skipped_ticks_; }
  const TriggerConfig& config() const { return config_; }
  // Nominal time of tick k of the current run, µs.
  uint64_t TickTimeUs(uint64_t k) const { return t0_ + (k * 1'000'000'000ull) / config_.rate_mhz; }

 private:
  struct LineState {
    uint64_t next_k = 0;  // tick of the next rise
    bool high = false;
    uint64_t fall_us = 0;  // when high
  };
  uint64_t RiseUs(int line, uint64_t k) const;
  // Last rise time of tick k over the enabled lines (T_k when none rises later).
  uint64_t ReportUs(uint64_t k) const;
  void SkipTo(uint64_t now_us);
  void CountLate(uint64_t now_us, uint64_t event_us);

  TriggerConfig config_;
  bool running_ = false;
  uint8_t enabled_mask_ = 0;
  uint64_t t0_ = 0;
  uint32_t first_seq_ = 0;  // seq of tick 0 of this run
  uint32_t next_seq_ = 0;   // seq of the next run's first tick
  uint64_t report_k_ = 0;   // tick of the next report
  LineState lines_[proto::kMaxLines];
  uint8_t high_mask_ = 0;
  uint32_t late_edges_ = 0;
  uint32_t skipped_ticks_ = 0;
};

}  // namespace rigcal::trigger_core
