#include "rigcal/trigger_core/scheduler.h"

namespace rigcal::trigger_core {

bool Scheduler::Configure(const TriggerConfig& config) {
  if (running_ || !CheckConfig(config).ok()) return false;
  config_ = config;
  return true;
}

bool Scheduler::Start(uint64_t now_us) {
  if (running_) return false;
  enabled_mask_ = config_.EnabledMask();
  if (enabled_mask_ == 0) return false;
  int64_t lead = 0;
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if (config_.lines[i].enabled && -config_.lines[i].RiseOffsetUs() > lead) {
      lead = -config_.lines[i].RiseOffsetUs();
    }
  }
  t0_ = now_us + static_cast<uint64_t>(lead);
  first_seq_ = next_seq_;
  report_k_ = 0;
  for (LineState& line : lines_) line = LineState{};
  high_mask_ = 0;
  running_ = true;
  return true;
}

void Scheduler::Stop(SchedulerListener* listener) {
  if (!running_) return;
  running_ = false;
  next_seq_ = first_seq_ + static_cast<uint32_t>(report_k_);
  for (LineState& line : lines_) line.high = false;
  if (high_mask_ != 0) {
    high_mask_ = 0;
    listener->OnLines(0);
  }
}

uint64_t Scheduler::RiseUs(int line, uint64_t k) const {
  return static_cast<uint64_t>(static_cast<int64_t>(TickTimeUs(k)) +
                               config_.lines[line].RiseOffsetUs());
}

uint64_t Scheduler::ReportUs(uint64_t k) const {
  uint64_t t = TickTimeUs(k);
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if ((enabled_mask_ >> i) & 1u) {
      const uint64_t rise = RiseUs(i, k);
      if (rise > t) t = rise;
    }
  }
  return t;
}

void Scheduler::CountLate(uint64_t now_us, uint64_t event_us) {
  if (now_us > event_us + kLateToleranceUs) ++late_edges_;
}

void Scheduler::SkipTo(uint64_t now_us) {
  // More than a period behind: jump to the tick whose time has just passed (k with
  // T_k <= now < T_k+1); the ticks before it are skipped whole.
  const uint64_t period = proto::PeriodUs(config_.rate_mhz);
  if (now_us < ReportUs(report_k_) + period) return;
  uint64_t k = now_us > t0_
                   ? ((now_us - t0_) * static_cast<uint64_t>(config_.rate_mhz)) / 1'000'000'000ull
                   : 0;
  if (k <= report_k_) return;
  skipped_ticks_ += static_cast<uint32_t>(k - report_k_);
  report_k_ = k;
  for (LineState& line : lines_) {
    if (line.next_k < k) line.next_k = k;
  }
}

void Scheduler::Poll(uint64_t now_us, SchedulerListener* listener) {
  if (!running_) return;
  SkipTo(now_us);
  const uint8_t before = high_mask_;
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if (((enabled_mask_ >> i) & 1u) == 0) continue;
    LineState& line = lines_[i];
    // Alternate fall / rise while due (width < period: a line's pulses never overlap).
    while (true) {
      if (line.high) {
        if (line.fall_us > now_us) break;
        CountLate(now_us, line.fall_us);
        line.high = false;
      } else {
        const uint64_t rise = RiseUs(i, line.next_k);
        if (rise > now_us || line.next_k > report_k_ + 1) break;
        CountLate(now_us, rise);
        line.high = true;
        line.fall_us = rise + config_.lines[i].width_us;
        ++line.next_k;
      }
    }
    high_mask_ =
        static_cast<uint8_t>(line.high ? (high_mask_ | (1u << i)) : (high_mask_ & ~(1u << i)));
  }
  if (high_mask_ != before) listener->OnLines(high_mask_);
  while (ReportUs(report_k_) <= now_us) {
    bool all_risen = true;
    for (int i = 0; i < proto::kMaxLines; ++i) {
      if (((enabled_mask_ >> i) & 1u) && lines_[i].next_k <= report_k_) all_risen = false;
    }
    if (!all_risen) break;
    proto::PulseReport report;
    report.line_mask = enabled_mask_;
    report.seq = first_seq_ + static_cast<uint32_t>(report_k_);
    report.mcu_time_us = TickTimeUs(report_k_);
    listener->OnPulse(report);
    ++report_k_;
  }
}

uint64_t Scheduler::NextEventUs() const {
  if (!running_) return UINT64_MAX;
  uint64_t next = ReportUs(report_k_);
  for (int i = 0; i < proto::kMaxLines; ++i) {
    if (((enabled_mask_ >> i) & 1u) == 0) continue;
    const LineState& line = lines_[i];
    const uint64_t t = line.high ? line.fall_us : RiseUs(i, line.next_k);
    if (t < next) next = t;
  }
  return next;
}

}  // namespace rigcal::trigger_core
