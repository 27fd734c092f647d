// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger_core/exposure_meter.h"

#include "rigcal/trigger_core/counter_extension.h"

namespace rigcal::trigger_core {

void ExposureMeter::Start() {
  for (LineState& line : lines_) line = LineState{};
}

void ExposureMeter::CountError() {
  errors_.store(errors_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

void ExposureMeter::OnCapture(int line, uint32_t count32, const Scheduler& scheduler) {
  LineState& s = lines_[line];
  if (!s.in_exposure) {
    uint32_t seq = 0;
    uint64_t rise_us = 0;
    if (!scheduler.LastRise(line, &seq, &rise_us)) return CountError();
    const uint64_t start_us = NearestTime(rise_us, count32);
    const uint64_t period_us = proto::PeriodUs(scheduler.config().rate_mhz);
    if (start_us < rise_us || start_us - rise_us >= period_us) return CountError();
    s = {true, seq, start_us};
    return;
  }
  s.in_exposure = false;
  const uint64_t end_us = NearestTime(s.start_us, count32);
  if (end_us < s.start_us || end_us - s.start_us > proto::kMaxExposureUs) return CountError();
  proto::ExposureReport report;
  report.seq = s.seq;
  report.line = static_cast<uint8_t>(line);
  report.start_us = s.start_us;
  report.duration_us = static_cast<uint32_t>(end_us - s.start_us);
  if (!reports_.Push(report)) {
    dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
}

void ExposureMeter::OnOvercapture(int line) {
  lines_[line].in_exposure = false;
  CountError();
}

bool ExposureMeter::Pop(proto::ExposureReport* report) {
  const proto::ExposureReport* front = reports_.Front();
  if (front == nullptr) return false;
  *report = *front;
  reports_.PopFront();
  return true;
}

}  // namespace rigcal::trigger_core
