// SPDX-License-Identifier: Apache-2.0
#include "peripherals.h"

#include "pinout.h"
#include "register_access.h"
#include "stm32f405_map.h"

namespace rigcal::board {
namespace {

using namespace stm32;

void AlternateFunction(const Pin& p, bool fast) {
  Modify32(p.port + kGpioModer, 3u << (2 * p.pin), 2u << (2 * p.pin));  // 10: alternate function
  const uint32_t afr = p.port + (p.pin < 8 ? kGpioAfrl : kGpioAfrh);
  const uint32_t shift = 4 * (p.pin % 8);
  Modify32(afr, 0xFu << shift, p.af << shift);
  if (fast) Modify32(p.port + kGpioOspeedr, 3u << (2 * p.pin), 2u << (2 * p.pin));
}

// One timer: prescaler, period, prescaler loaded (UG), count preset; `ccmr` for both registers.
void InitTimer(uint32_t tim, uint32_t psc, uint32_t arr, uint32_t count, uint32_t ccmr) {
  Write32(tim + kTimPsc, psc);
  Write32(tim + kTimArr, arr);
  Write32(tim + kTimEgr, kTimEgrUg);  // loads PSC, clears the count
  Write32(tim + kTimSr, 0);
  Write32(tim + kTimCnt, count & arr);
  Write32(tim + kTimCcmr1, ccmr);
  Write32(tim + kTimCcmr2, ccmr);
}

}  // namespace

void InitPins() {
  Set32(kRccAhb1Enr, kRccAhb1GpioA | kRccAhb1GpioB | kRccAhb1GpioC);
  for (const LinePins& l : kLinePins) {
    AlternateFunction(l.out, true);
    AlternateFunction(l.in, false);
  }
  AlternateFunction(kUsart1Tx, false);
  AlternateFunction(kUsart1Rx, false);
}

void InitUsart1(const ClockPlan& plan) {
  Set32(kRccApb2Enr, kRccApb2Usart1);
  Write32(kUsartBrr, plan.usart_brr);
  Write32(kUsartCr1, kUsartCr1Ue | kUsartCr1Rxneie | kUsartCr1Te | kUsartCr1Re);
}

void InitTimers(uint32_t psc, uint32_t preset_count) {
  Set32(kRccApb1Enr, kRccApb1Tim2 | kRccApb1Tim3 | kRccApb1Tim4 | kRccApb1Tim5);
  // Outputs: OCxM = force inactive (low) in both channels of each CCMR byte pair.
  const uint32_t forced_low = (kOcmForceInactive << 4) | (kOcmForceInactive << 12);
  // Inputs: CCxS = TIx, ICxF = 8 samples.
  const uint32_t inputs = (kCcsInputTi | (kIcFilterN8 << 4)) * 0x0101u;
  InitTimer(kTim2, psc, 0xFFFFFFFFu, preset_count, forced_low);
  InitTimer(kTim5, psc, 0xFFFFFFFFu, preset_count, forced_low);
  InitTimer(kTim3, psc, 0xFFFF, preset_count, inputs);
  InitTimer(kTim4, psc, 0xFFFF, preset_count, inputs);
  const uint32_t all_outputs = kCcerEnable * 0x1111u;  // CC1E..CC4E
  Write32(kTim2 + kTimCcer, all_outputs);
  Write32(kTim5 + kTimCcer, all_outputs);
  Write32(kTim3 + kTimCcer, 0);
  Write32(kTim4 + kTimCcer, 0);
  Write32(kTim5 + kTimSmcr, (kTim5ItrTim2 << kTimSmcrTsShift) | kTimSmcrSmsTrigger);
  Write32(kTim3 + kTimSmcr, (kTim3ItrTim2 << kTimSmcrTsShift) | kTimSmcrSmsTrigger);
  Write32(kTim4 + kTimSmcr, (kTim4ItrTim2 << kTimSmcrTsShift) | kTimSmcrSmsTrigger);
  Write32(kTim2 + kTimCr2, kTimCr2MmsEnable);
  Write32(kTim2 + kTimCr1, kTimCr1Cen);  // TRGO: TIM3, TIM4, TIM5 start on this count
}

void InitSysTick(const ClockPlan& plan) {
  Write32(kSysTickRvr, plan.systick_reload);
  Write32(kSysTickCvr, 0);
  Write32(kSysTickCsr, kSysTickCsrCoreClock | kSysTickCsrTickInt | kSysTickCsrEnable);
}

namespace {
// 4 priority bits in the top of each byte (PM0214 4.3.7): 0 is the highest.
void EnableIrq(uint32_t irq, uint32_t priority) {
  const uint32_t shift = 8 * (irq % 4);
  Modify32(kNvicIpr0 + (irq & ~3u), 0xFFu << shift, priority << shift);
  Write32(kNvicIser0 + 4 * (irq / 32), 1u << (irq % 32));
}
}  // namespace

void InitInterrupts() {
  // Compares (0) preempt captures (0x10), which preempt USART1 (0x20): nothing but a compare
  // service delays the arming of the next edge.
  EnableIrq(kTimIrqTim2, 0x00);
  EnableIrq(kTimIrqTim5, 0x00);
  EnableIrq(kTimIrqTim3, 0x10);
  EnableIrq(kTimIrqTim4, 0x10);
  EnableIrq(kUsart1Irq, 0x20);
}

}  // namespace rigcal::board
