// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger_core/ideal_line_timers.h"

namespace rigcal::trigger_core {

bool IdealLineTimers::Arm(int line, uint64_t t_us, bool high, uint32_t* late_us) {
  if (t_us <= now_us_) {
    armed_[line].armed = false;
    *late_us = static_cast<uint32_t>(now_us_ - t_us);
    return false;
  }
  armed_[line] = {true, t_us, high};
  return true;
}

void IdealLineTimers::SetLevel(int line, bool high, uint64_t t_us) {
  const bool was = ((levels_ >> line) & 1u) != 0;
  levels_ = static_cast<uint8_t>(high ? (levels_ | (1u << line)) : (levels_ & ~(1u << line)));
  if (was != high && sink_ != nullptr) sink_->OnEdge({t_us, line, high});
}

void IdealLineTimers::Drive(int line, bool high) {
  armed_[line].armed = false;
  SetLevel(line, high, now_us_);
}

void IdealLineTimers::Release(int line) {
  Drive(line, false);
  capture_[line] = trigger_protocol::ExposureInput::kNone;
}

void IdealLineTimers::StartCapture(int line, trigger_protocol::ExposureInput input) {
  capture_[line] = input;
}

uint64_t IdealLineTimers::NextEdgeUs() const {
  uint64_t next = UINT64_MAX;
  for (const Armed& a : armed_) {
    if (a.armed && a.t_us < next) next = a.t_us;
  }
  return next;
}

void IdealLineTimers::RunUntil(uint64_t until_us, CompareHandler* handler) {
  while (true) {
    int line = -1;
    for (int i = 0; i < trigger_protocol::kMaxLines; ++i) {
      if (armed_[i].armed && armed_[i].t_us <= until_us &&
          (line < 0 || armed_[i].t_us < armed_[line].t_us)) {
        line = i;
      }
    }
    if (line < 0) break;
    // The edge happens at its time; the clock only moves forward (a handler may have moved it
    // past later edges: they happened meanwhile, their interrupts come now).
    const uint64_t t_us = armed_[line].t_us;
    if (t_us > now_us_) now_us_ = t_us;
    armed_[line].armed = false;
    SetLevel(line, armed_[line].high, t_us);
    handler->OnCompare(line);
  }
  if (until_us > now_us_) now_us_ = until_us;
}

}  // namespace rigcal::trigger_core
