// SPDX-License-Identifier: Apache-2.0
#pragma once
// The clock tree of the trigger board and every constant derived from it, computed at compile
// time from the board's crystal (CMake TRIGGER_HSE_HZ: 8, 12, 16 or 25 MHz) so that no rate is
// written by hand anywhere else:
//
//   HSE (crystal) or HSI (16 MHz RC) -> /M -> VCO input 1..2 MHz (RM0090 6.3.2: 2 MHz limits
//   jitter) -> xN -> VCO 336 MHz -> /P=2 -> SYSCLK 168 MHz -> AHB /1 = 168 MHz (core, SysTick)
//                                    -> /Q=7 -> 48 MHz (USB, unused)
//   APB1 /4 = 42 MHz (max 42), its timers x2 = 84 MHz (TIM2..TIM5: µs counter, compares, captures)
//   APB2 /2 = 84 MHz (max 84): USART1
//   FLASH 5 wait states at 168 MHz and 2.7-3.6 V (RM0090 table 10), prefetch, I and D caches.
//
// The HSI fallback uses the same VCO (M = 16 / 2 MHz = 8, N = 168), so every derived constant
// holds whichever oscillator runs; only the accuracy changes (HSI: +-1 %).

#include <cstdint>

#include "rigcal/trigger_protocol/messages.h"

#ifndef RIGCAL_HSE_HZ
#define RIGCAL_HSE_HZ 8000000u
#endif

namespace rigcal::board {

inline constexpr uint32_t kHsiHz = 16'000'000;
inline constexpr uint32_t kVcoHz = 336'000'000;
inline constexpr uint32_t kSysclkHz = 168'000'000;
inline constexpr uint32_t kPllP = 2;
inline constexpr uint32_t kPllQ = 7;
inline constexpr uint32_t kAhbDiv = 1, kApb1Div = 4, kApb2Div = 2;
inline constexpr uint32_t kFlashWaitStates = 5;
inline constexpr uint32_t kTimerTickHz = 1'000'000;  // the µs counter
inline constexpr uint32_t kSysTickHz = 1'000;        // the main loop's wake-up

struct PllSetting {
  uint32_t m = 0;  // 0: no valid setting for the input
  uint32_t n = 0;
};

// The PLL input divider and multiplier for `input_hz`: the largest VCO input in [1, 2] MHz that
// divides both the input and the VCO frequency exactly (M in [2, 63], N in [50, 432]).
constexpr PllSetting PllFor(uint32_t input_hz) {
  for (uint32_t m = 2; m <= 63; ++m) {
    if (input_hz % m != 0) continue;
    const uint32_t vco_in = input_hz / m;
    if (vco_in > 2'000'000) continue;
    if (vco_in < 1'000'000) break;
    if (kVcoHz % vco_in != 0) continue;
    const uint32_t n = kVcoHz / vco_in;
    if (n >= 50 && n <= 432) return {m, n};
  }
  return {};
}

// RCC_PLLCFGR (RM0090 6.3.2): PLLM 5:0, PLLN 14:6, PLLP 17:16 (00 = /2), PLLSRC 22, PLLQ 27:24.
constexpr uint32_t PllCfgr(PllSetting pll, bool from_hse) {
  return pll.m | (pll.n << 6) | (((kPllP / 2) - 1) << 16) | ((from_hse ? 1u : 0u) << 22) |
         (kPllQ << 24);
}

struct ClockPlan {
  uint32_t hse_hz = 0;
  PllSetting pll_hse;
  PllSetting pll_hsi;
  uint32_t apb1_hz = 0;
  uint32_t apb2_hz = 0;
  uint32_t timer_hz = 0;        // TIM2..5 input: APB1 x 2 (RM0090 6.2: APB prescaler != 1)
  uint32_t usart_brr = 0;       // USART1_BRR at kLinkBaud, OVER8 = 0: round(apb2 / baud)
  int32_t baud_error_ppm = 0;   // actual / wanted - 1
  uint32_t timer_psc = 0;       // TIMx_PSC for the µs counter
  uint32_t systick_reload = 0;  // SYST_RVR for kSysTickHz from the core clock
};

constexpr ClockPlan MakeClockPlan(uint32_t hse_hz) {
  ClockPlan p;
  p.hse_hz = hse_hz;
  p.pll_hse = PllFor(hse_hz);
  p.pll_hsi = PllFor(kHsiHz);
  p.apb1_hz = kSysclkHz / kAhbDiv / kApb1Div;
  p.apb2_hz = kSysclkHz / kAhbDiv / kApb2Div;
  p.timer_hz = 2 * p.apb1_hz;
  const uint32_t baud = trigger_protocol::kLinkBaud;
  p.usart_brr = (p.apb2_hz + baud / 2) / baud;
  const int64_t actual_milli = 1000ll * p.apb2_hz / p.usart_brr;
  p.baud_error_ppm = static_cast<int32_t>((actual_milli - 1000ll * baud) * 1000 / baud);
  p.timer_psc = p.timer_hz / kTimerTickHz - 1;
  p.systick_reload = kSysclkHz / kSysTickHz - 1;
  return p;
}

// The plan checks every supported crystal passes (and the board's own, below).
constexpr bool PlanIsValid(const ClockPlan& p) {
  return p.hse_hz >= 4'000'000 && p.hse_hz <= 26'000'000             // the F405's HSE crystal range
         && p.pll_hse.m != 0 && p.pll_hsi.m != 0                     // exact 336 MHz VCO from both
         && p.apb1_hz <= 42'000'000 && p.apb2_hz <= 84'000'000       // bus limits (datasheet)
         && p.timer_hz % kTimerTickHz == 0 && p.timer_psc <= 0xFFFF  // exact µs
         && p.systick_reload <= 0xFFFFFF                             // 24-bit SysTick
         // The USART's receiver tolerates a few % of total deviation (RM0090 30.3.5); one side
         // may take 1 % at most.
         && p.baud_error_ppm <= 10'000 && p.baud_error_ppm >= -10'000;
}

static_assert(PlanIsValid(MakeClockPlan(8'000'000)), "8 MHz crystal");
static_assert(PlanIsValid(MakeClockPlan(12'000'000)), "12 MHz crystal");
static_assert(PlanIsValid(MakeClockPlan(16'000'000)), "16 MHz crystal");
static_assert(PlanIsValid(MakeClockPlan(25'000'000)), "25 MHz crystal");

// The board's plan (CMake TRIGGER_HSE_HZ).
inline constexpr ClockPlan kClockPlan = MakeClockPlan(RIGCAL_HSE_HZ);
static_assert(PlanIsValid(kClockPlan),
              "TRIGGER_HSE_HZ: no exact 168 MHz clock tree or baud rate from this crystal");
static_assert(kClockPlan.baud_error_ppm < 1'000, "115200 baud from 84 MHz: +0.02 % (RM0090)");

}  // namespace rigcal::board
