// SPDX-License-Identifier: Apache-2.0
#pragma once
// SystemInit-style start-up of the clock tree (clock_config.h), and a check of the timers' input
// clock against the core clock. Runs once, before anything uses a clock-derived rate.
//
//   1. PWR clock on, voltage scale 1 (168 MHz needs it).
//   2. HSE on; wait for HSERDY at most kHseStartupPolls reads (>= 100 ms at 16 MHz). Timeout:
//      HSE off, the PLL runs from HSI instead (status kClockHseFallback).
//   3. AHB /1, APB1 /4, APB2 /2 while still on HSI (no bus ever above its limit).
//   4. RCC_PLLCFGR from the plan, PLL on, wait for PLLRDY (timeout: kClockPllFailed, stay on HSI).
//   5. FLASH_ACR: 5 wait states, prefetch, I and D caches; read back until LATENCY is 5
//      (RM0090 3.5.1: before raising the clock).
//   6. SW = PLL, wait until SWS says PLL (timeout: kClockPllFailed).
// Every wait is bounded, so an emulator whose RCC reads 0 (QEMU) boots through the fallbacks.
//
// MeasureTimerClock then counts TIM2 at prescaler 1 against SysTick (core clock) for 10 ms: the
// µs prescaler comes from the plan when the measurement agrees within 2 %, else from the
// measurement (status kClockTimerMeasured; QEMU clocks its timers at 1 GHz).

#include <cstdint>

#include "clock_config.h"

namespace rigcal::board {

inline constexpr uint32_t kHseStartupPolls = 400'000;
inline constexpr uint32_t kPllLockPolls = 40'000;
inline constexpr uint32_t kSwitchPolls = 4'000;

// Returns ClockStatusBit flags (messages.h).
uint8_t ConfigureClockTree(const ClockPlan& plan);

struct TimerClock {
  uint32_t measured_hz = 0;
  uint32_t psc = 0;    // TIMx_PSC for the µs counter
  uint8_t status = 0;  // kClockTimerMeasured when the plan's prescaler was not used
};
TimerClock MeasureTimerClock(const ClockPlan& plan);

}  // namespace rigcal::board
