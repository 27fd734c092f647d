// SPDX-License-Identifier: Apache-2.0
#pragma once
// The trigger lines on the STM32F405's timers (pinout.h): LineTimers for the firmware core, and
// the interrupt service routines' bodies.
//
// Arm writes the line's compare register (CCRx = the edge's µs, low 32 bits), its output mode
// (OCxM: active / inactive on match) and enables its compare interrupt; the timer changes the
// pin when TIM2's count reaches it, to within one timer clock (12 ns) of the µs, whatever the
// CPU does. If the count has passed the edge when Arm reads it back and no match was flagged,
// the hardware will not make it: Arm disarms (OCxM frozen) and reports how late.
//
// Captures: a wired line's channel latches the count (16 bits, TIM3 / TIM4) at the edge the
// exposure meter expects; the interrupt turns it into the 32-bit count with TIM2's current count
// (a capture is read within 65 ms of its edge) and flips the polarity for the next edge.
//
// Under QEMU (no compare or capture model) ServiceDueCompares makes the armed edges that are
// due from the main loop: the same path, called with the interrupts masked. On a board it only
// finds edges whose interrupt is pending.
//
// Contexts: as LineTimers; the Service* functions in the timer interrupts (or masked main loop).

#include <cstdint>

#include "rigcal/trigger_core/line_timers.h"
#include "rigcal/trigger_core/trigger_app.h"

namespace rigcal::board {

class Stm32LineTimers final : public trigger_core::LineTimers {
 public:
  bool Arm(int line, uint64_t t_us, bool high, uint32_t* late_us) override;
  void Drive(int line, bool high) override;
  void Release(int line) override;
  void StartCapture(int line, trigger_protocol::ExposureInput input) override;

  // Compare interrupt of TIM2 or TIM5 (`timer` = its base): the lines whose edge happened.
  void ServiceCompareInterrupt(uint32_t timer, trigger_core::TriggerApp* app);
  // Capture interrupt of TIM3 or TIM4.
  void ServiceCaptureInterrupt(uint32_t timer, trigger_core::TriggerApp* app);
  // Main loop, interrupts masked: the armed edges whose time TIM2's count has reached.
  void ServiceDueCompares(trigger_core::TriggerApp* app);
  // µs from TIM2's count `now32` to the earliest armed edge (UINT32_MAX when none is armed).
  uint32_t UsToNextEdge(uint32_t now32) const;

 private:
  struct Armed {
    bool armed = false;
    uint32_t ccr = 0;
  };
  void SetCapturePolarity(int line, bool active_edge);
  Armed armed_[trigger_protocol::kMaxLines];
  trigger_protocol::ExposureInput input_[trigger_protocol::kMaxLines] = {};
};

}  // namespace rigcal::board
