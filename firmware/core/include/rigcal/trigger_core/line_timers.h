// SPDX-License-Identifier: Apache-2.0
#pragma once
// LineTimers: the hardware that drives the trigger lines and listens to the cameras' exposure
// outputs, as the firmware core sees it. The board implements it with timer output-compare
// channels (one per line) and input-capture channels (one per wired exposure input); host runs use
// IdealLineTimers (ideal_line_timers.h).
//
// Output compare: a line is armed with one edge at a time. The hardware changes the line's level
// when the µs counter reaches the edge's time, whatever the CPU is doing; the compare interrupt
// then calls Scheduler::OnCompare, which arms the line's next edge.
//
// Contexts: Arm / Drive are called from the compare context (the timer interrupt, or the main
// loop with that interrupt masked) and by Scheduler::Start before any compare is armed; Release
// and StartCapture from the main loop (Stop / Start).

#include <cstdint>

#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger_core {

class LineTimers {
 public:
  // Arms `line` to go high (`high`) or low when the µs counter reaches `t_us`. Returns true when
  // armed in time. False: `t_us` had already passed (by *late_us >= 0 µs) when the compare was
  // written, the hardware will not produce the edge, and the line keeps its level.
  virtual bool Arm(int line, uint64_t t_us, bool high, uint32_t* late_us) = 0;
  // Sets the line's level now (a late edge); no compare stays armed.
  virtual void Drive(int line, bool high) = 0;
  // Drives the line low, cancels its compare and its exposure capture (Stop).
  virtual void Release(int line) = 0;
  // Starts capturing `line`'s exposure input: first the edge to `input`'s active level.
  virtual void StartCapture(int line, trigger_protocol::ExposureInput input) = 0;

 protected:
  ~LineTimers() = default;
};

}  // namespace rigcal::trigger_core
