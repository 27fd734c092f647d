// SPDX-License-Identifier: Apache-2.0
#pragma once
// Start-up of the board's peripherals once the clocks run (clock_tree.h): pins, USART1, the four
// synchronised timers, SysTick and the interrupt controller. Each takes its rates from the
// clock plan or the timer-clock measurement; nothing here knows a frequency.

#include <cstdint>

#include "clock_config.h"

namespace rigcal::board {

// Pins of every line, exposure input and the host link to their alternate functions; the
// outputs at high speed (OSPEEDR 10: < 10 ns edges at 3.3 V into 50 pF).
void InitPins();
// USART1 at kLinkBaud (BRR from the plan), receive interrupt on.
void InitUsart1(const ClockPlan& plan);
// TIM2 (master, 32-bit µs count starting at `preset_count`), TIM5 (outputs 0-3), TIM3 / TIM4
// (captures) at prescaler `psc`: every output channel forced low, every capture channel an
// input on its pin with an 8-sample filter (95 ns at 84 MHz), disabled. Then TIM2 starts and
// its trigger starts the others on the same count.
void InitTimers(uint32_t psc, uint32_t preset_count);
// SysTick at kSysTickHz from the core clock (wakes the main loop), with its interrupt.
void InitSysTick(const ClockPlan& plan);
// Interrupt priorities and enables: the compare timers (TIM2, TIM5) highest, the capture timers
// (TIM3, TIM4) next, USART1 last (an edge's re-arming never waits for a capture or a byte).
void InitInterrupts();

}  // namespace rigcal::board
