// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger_core/scheduler.h"

namespace rigcal::trigger_core {
namespace {

// Single-writer increment of a counter the main loop reads.
void Bump(std::atomic<uint32_t>* counter, uint64_t by = 1) {
  counter->store(counter->load(std::memory_order_relaxed) + static_cast<uint32_t>(by),
                 std::memory_order_relaxed);
}

}  // namespace

bool Scheduler::Configure(const TriggerConfig& config) {
  if (running() || !CheckConfig(config).ok()) return false;
  config_ = config;
  return true;
}

void Scheduler::Advance(TickClock* clock) const {
  // No division: the compare interrupt runs this for every edge.
  clock->k += 1;
  clock->t_us += period_us_;
  clock->frac += period_rem_;
  if (clock->frac >= config_.rate_mhz) {
    clock->frac -= config_.rate_mhz;
    clock->t_us += 1;
  }
}

Scheduler::TickClock Scheduler::ClockAt(uint64_t k) const {
  const uint64_t scaled = k * 1'000'000'000ull;
  return {k, t0_ + scaled / config_.rate_mhz, static_cast<uint32_t>(scaled % config_.rate_mhz)};
}

uint64_t Scheduler::RiseUs(int line, const TickClock& clock) const {
  return static_cast<uint64_t>(static_cast<int64_t>(clock.t_us) +
                               config_.lines[line].RiseOffsetUs());
}

bool Scheduler::Start(uint64_t now_us, LineTimers* timers) {
  if (running()) return false;
  enabled_mask_ = config_.EnabledMask();
  if (enabled_mask_ == 0) return false;
  int64_t lead = 0;
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if (config_.lines[i].enabled && -config_.lines[i].RiseOffsetUs() > lead) {
      lead = -config_.lines[i].RiseOffsetUs();
    }
  }
  t0_ = now_us + kArmLeadUs + static_cast<uint64_t>(lead);
  period_us_ = static_cast<uint32_t>(1'000'000'000ull / config_.rate_mhz);
  period_rem_ = static_cast<uint32_t>(1'000'000'000ull % config_.rate_mhz);
  first_seq_ = next_seq();
  report_ = ClockAt(0);
  skip_from_k_ = skip_before_k_ = 0;
  for (LineState& line : lines_) line = LineState{};
  running_.store(true, std::memory_order_release);
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if ((enabled_mask_ >> i) & 1u) {
      lines_[i].tick = ClockAt(0);
      ArmRise(i, timers);
    }
  }
  return true;
}

void Scheduler::Stop(LineTimers* timers) {
  if (!running()) return;
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if ((enabled_mask_ >> i) & 1u) timers->Release(i);
  }
  running_.store(false, std::memory_order_release);
}

void Scheduler::ArmRise(int line, LineTimers* timers) {
  LineState& s = lines_[line];
  if (s.tick.k >= skip_from_k_ && s.tick.k < skip_before_k_) s.tick = ClockAt(skip_before_k_);
  uint32_t late_us = 0;
  while (!timers->Arm(line, RiseUs(line, s.tick), true, &late_us)) {
    // Too late for this rise: skip to the first tick whose rise is kArmLeadUs ahead of now.
    const uint64_t now_us = RiseUs(line, s.tick) + late_us;
    const int64_t first_rise = static_cast<int64_t>(t0_) + config_.lines[line].RiseOffsetUs();
    const uint64_t since_t0 = now_us + kArmLeadUs - static_cast<uint64_t>(first_rise);
    const uint64_t scaled = since_t0 * config_.rate_mhz;
    uint64_t k = scaled / 1'000'000'000ull + (scaled % 1'000'000'000ull != 0 ? 1 : 0);
    if (k <= s.tick.k) k = s.tick.k + 1;
    Skip(s.tick.k, k);
    s.tick = ClockAt(k);
  }
  s.high = false;
  s.armed_us = RiseUs(line, s.tick);
  QueueReports();  // ticks this line skipped may complete (as skipped) now
}

void Scheduler::Skip(uint64_t from_k, uint64_t before_k) {
  if (report_.k >= skip_before_k_) {  // the last range is behind the reports: start a new one
    skip_from_k_ = from_k;
    skip_before_k_ = before_k;
    return;
  }
  if (from_k < skip_from_k_) skip_from_k_ = from_k;
  if (before_k > skip_before_k_) skip_before_k_ = before_k;
}

void Scheduler::OnCompare(int line, LineTimers* timers) {
  if (!running() || ((enabled_mask_ >> line) & 1u) == 0) return;
  LineState& s = lines_[line];
  if (!s.high) {  // the rise of tick s.tick.k happened: arm the fall
    s.last_rise_us = s.armed_us;
    s.rises = s.tick.k + 1;
    const uint64_t fall_us = s.armed_us + config_.lines[line].width_us;
    uint32_t late_us = 0;
    if (timers->Arm(line, fall_us, false, &late_us)) {
      s.high = true;
      s.armed_us = fall_us;
    } else {  // held off past the fall: end the pulse now, then go on to the next rise
      timers->Drive(line, false);
      Bump(&late_edges_);
      Advance(&s.tick);
      ArmRise(line, timers);
    }
    QueueReports();
    return;
  }
  Advance(&s.tick);  // the fall happened: arm the next tick's rise
  ArmRise(line, timers);
}

void Scheduler::QueueReports() {
  while (true) {
    if (report_.k >= skip_from_k_ && report_.k < skip_before_k_) {
      Bump(&skipped_ticks_, skip_before_k_ - report_.k);
      report_ = ClockAt(skip_before_k_);
      next_seq_.store(first_seq_ + static_cast<uint32_t>(report_.k), std::memory_order_release);
    }
    for (int i = 0; i < proto::kMaxLines; ++i) {
      if (((enabled_mask_ >> i) & 1u) && lines_[i].rises <= report_.k) return;
    }
    proto::PulseReport report;
    report.line_mask = enabled_mask_;
    report.seq = first_seq_ + static_cast<uint32_t>(report_.k);
    report.mcu_time_us = report_.t_us;
    if (!reports_.Push(report)) Bump(&dropped_reports_);
    Advance(&report_);
    next_seq_.store(first_seq_ + static_cast<uint32_t>(report_.k), std::memory_order_release);
  }
}

bool Scheduler::LastRise(int line, uint32_t* seq, uint64_t* rise_us) const {
  const volatile LineState& s = lines_[line];
  // The capture interrupt may be preempted by the compare interrupt: read until both fields
  // belong to the same rise.
  uint64_t rises = 0;
  do {
    rises = s.rises;
    *rise_us = s.last_rise_us;
  } while (rises != s.rises);
  if (!running() || rises == 0) return false;
  *seq = first_seq_ + static_cast<uint32_t>(rises - 1);
  return true;
}

uint64_t Scheduler::NextRiseUs(int line) const {
  const LineState& s = lines_[line];
  if (!s.high) return s.armed_us;
  TickClock next = s.tick;
  Advance(&next);
  return RiseUs(line, next);
}

bool Scheduler::PopReport(uint64_t now_us, proto::PulseReport* report) {
  const proto::PulseReport* front = reports_.Front();
  if (front == nullptr || front->mcu_time_us > now_us) return false;
  *report = *front;
  reports_.PopFront();
  return true;
}

uint64_t Scheduler::NextReportUs() const {
  const proto::PulseReport* front = reports_.Front();
  return front == nullptr ? UINT64_MAX : front->mcu_time_us;
}

}  // namespace rigcal::trigger_core
