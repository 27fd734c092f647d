// SPDX-License-Identifier: Apache-2.0
#include "clock_tree.h"

#include "register_access.h"
#include "stm32f405_map.h"

namespace rigcal::board {
namespace {

namespace proto = ::rigcal::trigger_protocol;
using namespace stm32;

// Reads `address` until (value & mask) == want, at most `polls` times.
bool WaitFor(uint32_t address, uint32_t mask, uint32_t want, uint32_t polls) {
  for (uint32_t i = 0; i < polls; ++i) {
    if ((Read32(address) & mask) == want) return true;
  }
  return false;
}

}  // namespace

uint8_t ConfigureClockTree(const ClockPlan& plan) {
  uint8_t status = 0;
  Set32(kRccApb1Enr, kRccApb1Pwr);
  Set32(kPwrCr, kPwrCrVos);
  Set32(kRccCr, kRccCrHseOn);
  bool from_hse = WaitFor(kRccCr, kRccCrHseRdy, kRccCrHseRdy, kHseStartupPolls);
  if (!from_hse) {
    Clear32(kRccCr, kRccCrHseOn);
    status |= proto::kClockHseFallback;
  }
  Write32(kRccCfgr, kRccCfgrHpreDiv1 | kRccCfgrPpre1Div4 | kRccCfgrPpre2Div2);
  Write32(kRccPllCfgr, PllCfgr(from_hse ? plan.pll_hse : plan.pll_hsi, from_hse));
  Set32(kRccCr, kRccCrPllOn);
  if (!WaitFor(kRccCr, kRccCrPllRdy, kRccCrPllRdy, kPllLockPolls)) {
    return status | proto::kClockPllFailed;
  }
  Write32(kFlashAcr, kFlashAcrPrften | kFlashAcrIcen | kFlashAcrDcen | kFlashWaitStates);
  if (!WaitFor(kFlashAcr, kFlashAcrLatencyMask, kFlashWaitStates, kSwitchPolls)) {
    return status | proto::kClockPllFailed;  // never switch before the wait states hold
  }
  Modify32(kRccCfgr, kRccCfgrSwMask, kRccCfgrSwPll);
  if (!WaitFor(kRccCfgr, kRccCfgrSwsMask, kRccCfgrSwsPll, kSwitchPolls)) {
    status |= proto::kClockPllFailed;
  }
  return status;
}

TimerClock MeasureTimerClock(const ClockPlan& plan) {
  constexpr uint32_t kWindowCycles = kSysclkHz / 100;  // 10 ms of core clock
  Set32(kRccApb1Enr, kRccApb1Tim2);
  Write32(kTim2 + kTimPsc, 0);
  Write32(kTim2 + kTimArr, 0xFFFFFFFFu);
  Write32(kTim2 + kTimEgr, kTimEgrUg);
  Write32(kTim2 + kTimCnt, 0);
  Write32(kTim2 + kTimCr1, kTimCr1Cen);
  Write32(kSysTickRvr, 0xFFFFFF);
  Write32(kSysTickCvr, 0);
  Write32(kSysTickCsr, kSysTickCsrCoreClock | kSysTickCsrEnable);
  const uint32_t s0 = Read32(kSysTickCvr);
  const uint32_t c0 = Read32(kTim2 + kTimCnt);
  uint32_t cycles = 0;
  while (cycles < kWindowCycles) cycles = (s0 - Read32(kSysTickCvr)) & 0xFFFFFF;  // counts down
  const uint32_t c1 = Read32(kTim2 + kTimCnt);
  const uint32_t s1 = Read32(kSysTickCvr);
  cycles = (s0 - s1) & 0xFFFFFF;
  Write32(kTim2 + kTimCr1, 0);
  Write32(kSysTickCsr, 0);
  TimerClock out;
  out.measured_hz =
      static_cast<uint32_t>(uint64_t{c1 - c0} * kSysclkHz / (cycles == 0 ? 1 : cycles));
  const uint32_t tolerance = plan.timer_hz / 50;  // 2 %
  const uint32_t diff = out.measured_hz > plan.timer_hz ? out.measured_hz - plan.timer_hz
                                                        : plan.timer_hz - out.measured_hz;
  if (diff <= tolerance) {
    out.psc = plan.timer_psc;
  } else {
    const uint32_t mhz = (out.measured_hz + kTimerTickHz / 2) / kTimerTickHz;
    out.psc = mhz == 0 ? 0 : (mhz > 0x10000 ? 0xFFFF : mhz - 1);
    out.status = proto::kClockTimerMeasured;
  }
  return out;
}

}  // namespace rigcal::board
