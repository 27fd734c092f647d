// SPDX-License-Identifier: Apache-2.0
#include "stm32_line_timers.h"

#include "pinout.h"
#include "register_access.h"
#include "stm32f405_map.h"

namespace rigcal::board {
namespace {

using namespace stm32;
namespace proto = ::rigcal::trigger_protocol;

uint32_t CcmrOf(uint32_t timer, uint32_t channel) {
  return timer + (channel <= 2 ? kTimCcmr1 : kTimCcmr2);
}
uint32_t CcmrShift(uint32_t channel) { return (channel % 2 == 1) ? 0 : 8; }
uint32_t CcrOf(uint32_t timer, uint32_t channel) { return timer + kTimCcr1 + 4 * (channel - 1); }

void SetOutputMode(uint32_t timer, uint32_t channel, uint32_t ocm) {
  const uint32_t shift = CcmrShift(channel) + 4;
  Modify32(CcmrOf(timer, channel), 7u << shift, ocm << shift);
}

// SR flags are cleared by writing 0 (rc_w0); writing 1 leaves a flag as it is.
void ClearFlags(uint32_t timer, uint32_t flags) { Write32(timer + kTimSr, ~flags); }

uint32_t Now32() { return Read32(kTim2 + kTimCnt); }

int LineOf(uint32_t timer, uint32_t channel, bool output) {
  for (int line = 0; line < proto::kMaxLines; ++line) {
    const LinePins& p = kLinePins[line];
    if (output ? (p.out_timer == timer && p.out_channel == channel)
               : (p.in_timer == timer && p.in_channel == channel)) {
      return line;
    }
  }
  return -1;
}

}  // namespace

bool Stm32LineTimers::Arm(int line, uint64_t t_us, bool high, uint32_t* late_us) {
  const LinePins& p = kLinePins[line];
  const uint32_t flag = 1u << p.out_channel;
  const uint32_t ccr = static_cast<uint32_t>(t_us);
  ClearFlags(p.out_timer, flag);
  SetOutputMode(p.out_timer, p.out_channel, high ? kOcmActiveOnMatch : kOcmInactiveOnMatch);
  Write32(CcrOf(p.out_timer, p.out_channel), ccr);
  Set32(p.out_timer + kTimDier, flag);
  const int32_t ahead = static_cast<int32_t>(ccr - Now32());
  if (ahead > 0 || (Read32(p.out_timer + kTimSr) & flag) != 0) {  // armed, or matched already
    armed_[line] = {true, ccr};
    return true;
  }
  SetOutputMode(p.out_timer, p.out_channel, kOcmFrozen);  // keep the level, never match later
  Clear32(p.out_timer + kTimDier, flag);
  armed_[line].armed = false;
  *late_us = static_cast<uint32_t>(-static_cast<int64_t>(ahead));
  return false;
}

void Stm32LineTimers::Drive(int line, bool high) {
  const LinePins& p = kLinePins[line];
  SetOutputMode(p.out_timer, p.out_channel, high ? kOcmForceActive : kOcmForceInactive);
  Clear32(p.out_timer + kTimDier, 1u << p.out_channel);
  armed_[line].armed = false;
}

void Stm32LineTimers::Release(int line) {
  Drive(line, false);
  const LinePins& p = kLinePins[line];
  Clear32(p.in_timer + kTimDier, 1u << p.in_channel);
  Clear32(p.in_timer + kTimCcer, 0xFu << (4 * (p.in_channel - 1)));
  input_[line] = proto::ExposureInput::kNone;
}

void Stm32LineTimers::SetCapturePolarity(int line, bool active_edge) {
  const LinePins& p = kLinePins[line];
  // The active edge is rising for an active-high input; CCxP = 1 captures falling edges.
  const bool rising = active_edge == (input_[line] == proto::ExposureInput::kActiveHigh);
  const uint32_t shift = 4 * (p.in_channel - 1);
  Modify32(p.in_timer + kTimCcer, 0xFu << shift,
           (kCcerEnable | (rising ? 0 : kCcerFalling)) << shift);
}

void Stm32LineTimers::StartCapture(int line, proto::ExposureInput input) {
  const LinePins& p = kLinePins[line];
  input_[line] = input;
  if (input == proto::ExposureInput::kNone) return;
  SetCapturePolarity(line, true);
  ClearFlags(p.in_timer, (1u << p.in_channel) | (1u << (8 + p.in_channel)));
  Set32(p.in_timer + kTimDier, 1u << p.in_channel);
}

void Stm32LineTimers::ServiceCompareInterrupt(uint32_t timer, trigger_core::TriggerApp* app) {
  const uint32_t pending = Read32(timer + kTimSr) & Read32(timer + kTimDier) & 0x1Eu;
  if (pending == 0) return;
  ClearFlags(timer, pending);
  const uint32_t now = Now32();
  for (uint32_t channel = 1; channel <= 4; ++channel) {
    if ((pending & (1u << channel)) == 0) continue;
    const int line = LineOf(timer, channel, true);
    // A flag of an edge that was since disarmed, or not reached yet, is stale.
    if (line < 0 || !armed_[line].armed || static_cast<int32_t>(now - armed_[line].ccr) < 0) {
      continue;
    }
    armed_[line].armed = false;
    app->OnCompare(line);
  }
}

void Stm32LineTimers::ServiceCaptureInterrupt(uint32_t timer, trigger_core::TriggerApp* app) {
  const uint32_t sr = Read32(timer + kTimSr);
  const uint32_t pending = sr & Read32(timer + kTimDier) & 0x1Eu;
  for (uint32_t channel = 1; channel <= 4; ++channel) {
    if ((pending & (1u << channel)) == 0) continue;
    const uint32_t captured = Read32(CcrOf(timer, channel)) & 0xFFFF;  // clears CCxIF
    const int line = LineOf(timer, channel, false);
    if (line < 0) continue;
    if ((sr & (1u << (8 + channel))) != 0) {  // CCxOF: an edge was lost
      ClearFlags(timer, 1u << (8 + channel));
      app->OnOvercapture(line);
    } else {
      // The capture lies less than 2^16 µs before now: the count's high bits are now's.
      const uint32_t now = Now32();
      const uint32_t elapsed = (now - captured) & 0xFFFF;
      app->OnCapture(line, now - elapsed);
    }
    SetCapturePolarity(line, app->meter().ExpectsStart(line));
  }
}

void Stm32LineTimers::ServiceDueCompares(trigger_core::TriggerApp* app) {
  const uint32_t now = Now32();
  for (int line = 0; line < proto::kMaxLines; ++line) {
    if (!armed_[line].armed || static_cast<int32_t>(now - armed_[line].ccr) < 0) continue;
    const LinePins& p = kLinePins[line];
    ClearFlags(p.out_timer, 1u << p.out_channel);
    armed_[line].armed = false;
    app->OnCompare(line);
  }
}

uint32_t Stm32LineTimers::UsToNextEdge(uint32_t now32) const {
  uint32_t next = UINT32_MAX;
  for (const Armed& a : armed_) {
    if (!a.armed) continue;
    const int32_t ahead = static_cast<int32_t>(a.ccr - now32);
    const uint32_t us = ahead < 0 ? 0 : static_cast<uint32_t>(ahead);
    if (us < next) next = us;
  }
  return next;
}

}  // namespace rigcal::board
