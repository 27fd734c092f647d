// SPDX-License-Identifier: Apache-2.0
// The board's clock tree and peripheral start-up (firmware/board/stm32f405 clock_tree.cc,
// peripherals.cc) run against a fake STM32F405 register map (fake_stm32.h): the values written
// and their order are checked against RM0090 for an 8 MHz and a 25 MHz crystal, the HSE timeout
// fallback, a PLL that does not lock, and the timer-clock measurement (84 MHz; QEMU's 1 GHz).
// Every expected value below is worked out from the reference manual's field layout by hand,
// not taken from the code under test.
#include <gtest/gtest.h>

#include "clock_config.h"
#include "clock_tree.h"
#include "fake_stm32.h"
#include "peripherals.h"
#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::board {
namespace {

using testing::FakeStm32;
namespace proto = ::rigcal::trigger_protocol;

// RCC_PLLCFGR (RM0090 6.3.2): PLLM 5:0, PLLN 14:6, PLLP 17:16 (00: /2), PLLSRC 22, PLLQ 27:24.
//   8 MHz HSE:  M=4 (2 MHz VCO input), N=168, P=/2, HSE, Q=7 -> 0x0740'2A04
//   25 MHz HSE: M=25 (1 MHz; 25/2 MHz is not a divisor of 336 MHz), N=336 -> 0x0740'5419
//   16 MHz HSI: M=8 (2 MHz), N=168, HSI                     -> 0x0700'2A08
constexpr uint32_t kPllCfgr8MHz = 0x07402A04;
constexpr uint32_t kPllCfgr25MHz = 0x07405419;
constexpr uint32_t kPllCfgrHsi = 0x07002A08;
// RCC_CFGR (6.3.3): HPRE 7:4 = 0000 (/1), PPRE1 12:10 = 101 (/4), PPRE2 15:13 = 100 (/2), SW 1:0.
constexpr uint32_t kCfgrPrescalers = 0x00009400;
constexpr uint32_t kCfgrOnPll = 0x00009402;
// FLASH_ACR (3.9.1): LATENCY 2:0 = 5 WS, PRFTEN 8, ICEN 9, DCEN 10.
constexpr uint32_t kFlashAcrValue = 0x00000705;

void ExpectStartUpOrder(const FakeStm32& f) {
  using namespace stm32;
  const int pwr = f.FirstWrite(kPwrCr, kPwrCrVos);
  const int prescalers = f.FirstWrite(kRccCfgr, kCfgrPrescalers);
  const int pllcfgr = f.FirstWrite(kRccPllCfgr, 0);
  const int pll_on = f.FirstWrite(kRccCr, kRccCrPllOn);
  const int flash = f.FirstWrite(stm32::kFlashAcr, kFlashAcrValue);
  const int switch_on = f.FirstWrite(kRccCfgr, kRccCfgrSwPll);
  ASSERT_GE(pwr, 0);
  EXPECT_GE(f.FirstWrite(kRccApb1Enr, kRccApb1Pwr), 0);
  EXPECT_LT(pwr, pll_on) << "voltage scale 1 before the PLL";
  EXPECT_LT(prescalers, switch_on) << "APB1 /4, APB2 /2 before 168 MHz reaches them";
  EXPECT_LT(pllcfgr, pll_on) << "PLL configured while off";
  EXPECT_LT(pll_on, flash);
  EXPECT_LT(flash, switch_on) << "5 wait states before the switch (RM0090 3.5.1)";
  EXPECT_GE(f.reads(stm32::kFlashAcr), 1u) << "FLASH_ACR read back before the switch";
  EXPECT_GE(f.reads(kRccCfgr), 1u) << "SWS waited on";
}

TEST(ClockTree, EightMegahertzCrystalRunsThePllAt168MHz) {
  FakeStm32 f(/*hse_ready_after_reads=*/500);
  EXPECT_EQ(ConfigureClockTree(MakeClockPlan(8'000'000)), 0);
  using namespace stm32;
  EXPECT_EQ(f.ValuesWritten(kRccPllCfgr), std::vector<uint32_t>{kPllCfgr8MHz});
  EXPECT_EQ(f.ValuesWritten(kRccCfgr), (std::vector<uint32_t>{kCfgrPrescalers, kCfgrOnPll}));
  EXPECT_EQ(f.ValuesWritten(stm32::kFlashAcr), std::vector<uint32_t>{kFlashAcrValue});
  EXPECT_LT(f.FirstWrite(kRccCr, kRccCrHseOn), f.FirstWrite(kRccCr, kRccCrPllOn));
  EXPECT_GT(f.reads(kRccCr), 500u) << "waited for HSERDY";
  EXPECT_EQ(f.FirstWrite(kRccCr, 0, kRccCrHseOn), -1) << "the crystal stays on";
  EXPECT_EQ(f.Peek(kRccCr) & (kRccCrHseOn | kRccCrPllOn), kRccCrHseOn | kRccCrPllOn);
  ExpectStartUpOrder(f);
}

TEST(ClockTree, TwentyFiveMegahertzCrystal) {
  FakeStm32 f(/*hse_ready_after_reads=*/20);
  EXPECT_EQ(ConfigureClockTree(MakeClockPlan(25'000'000)), 0);
  EXPECT_EQ(f.ValuesWritten(stm32::kRccPllCfgr), std::vector<uint32_t>{kPllCfgr25MHz});
  EXPECT_EQ(f.ValuesWritten(stm32::kRccCfgr).back(), kCfgrOnPll);
  ExpectStartUpOrder(f);
}

TEST(ClockTree, ACrystalThatDoesNotStartFallsBackToTheHsiWithTheStatusBit) {
  FakeStm32 f(/*hse_ready_after_reads=*/-1);
  EXPECT_EQ(ConfigureClockTree(MakeClockPlan(8'000'000)), proto::kClockHseFallback);
  using namespace stm32;
  EXPECT_GE(f.reads(kRccCr), kHseStartupPolls) << "gave up before the timeout";
  EXPECT_LT(f.reads(kRccCr), kHseStartupPolls + kPllLockPolls);
  const int hse_off = f.FirstWrite(kRccCr, 0, kRccCrHseOn | kRccCrPllOn);
  EXPECT_GT(hse_off, f.FirstWrite(kRccCr, kRccCrHseOn)) << "HSE switched off again";
  EXPECT_EQ(f.ValuesWritten(kRccPllCfgr), std::vector<uint32_t>{kPllCfgrHsi});
  EXPECT_EQ(f.ValuesWritten(kRccCfgr).back(), kCfgrOnPll) << "168 MHz from the HSI";
  ExpectStartUpOrder(f);
  // The same VCO: every derived constant holds on the fallback.
  EXPECT_EQ(MakeClockPlan(8'000'000).pll_hsi.n * (16'000'000 / MakeClockPlan(8'000'000).pll_hsi.m),
            336'000'000u);
}

TEST(ClockTree, APllThatDoesNotLockNeverBecomesTheSystemClock) {
  FakeStm32 f(/*hse_ready_after_reads=*/5, /*pll_locks=*/false);
  EXPECT_EQ(ConfigureClockTree(MakeClockPlan(8'000'000)), proto::kClockPllFailed);
  EXPECT_GE(f.reads(stm32::kRccCr), kPllLockPolls);
  EXPECT_EQ(f.FirstWrite(stm32::kRccCfgr, stm32::kRccCfgrSwPll), -1);
  EXPECT_TRUE(f.ValuesWritten(stm32::kFlashAcr).empty());
}

TEST(ClockPlan, DerivedConstantsMatchTheReferenceManual) {
  for (uint32_t hse : {8'000'000u, 12'000'000u, 16'000'000u, 25'000'000u}) {
    SCOPED_TRACE(hse);
    const ClockPlan p = MakeClockPlan(hse);
    EXPECT_EQ(p.apb1_hz, 42'000'000u);
    EXPECT_EQ(p.apb2_hz, 84'000'000u);
    EXPECT_EQ(p.timer_hz, 84'000'000u);  // APB1 prescaler != 1: timers at twice APB1
    // RM0090 table 136 (fPCLK 84 MHz, OVER8 = 0): 115.2 kbps -> USARTDIV 45.5625 (mantissa 45,
    // fraction 9/16), actual 115.226 kbps, error 0.02 %.
    EXPECT_EQ(p.usart_brr, (45u << 4) | 9u);
    EXPECT_NEAR(p.baud_error_ppm, 227, 1);
    EXPECT_EQ(p.timer_psc, 83u);            // 84 MHz / 84 = 1 MHz
    EXPECT_EQ(p.systick_reload, 167'999u);  // 168 MHz / 168000 = 1 kHz
    const uint32_t vco_in = hse / p.pll_hse.m;
    EXPECT_GE(vco_in, 1'000'000u);
    EXPECT_LE(vco_in, 2'000'000u);
    EXPECT_EQ(vco_in * p.pll_hse.n / 2, 168'000'000u);
  }
  // 12 and 16 MHz get the recommended 2 MHz VCO input.
  EXPECT_EQ(PllCfgr(MakeClockPlan(12'000'000).pll_hse, true), 0x07402A06u);
  EXPECT_EQ(PllCfgr(MakeClockPlan(16'000'000).pll_hse, true), 0x07402A08u);
  EXPECT_FALSE(PlanIsValid(MakeClockPlan(27'000'000)));  // outside the F405's crystal range
}

TEST(TimerClock, MeasuredAgainstTheCoreClock) {
  {
    FakeStm32 f(5, true, 84'000'000);
    const TimerClock t = MeasureTimerClock(MakeClockPlan(8'000'000));
    EXPECT_NEAR(t.measured_hz, 84'000'000.0, 84'000.0);
    EXPECT_EQ(t.psc, 83u);
    EXPECT_EQ(t.status, 0);
  }
  {
    FakeStm32 f(5, true, 1'000'000'000);  // QEMU's timers
    const TimerClock t = MeasureTimerClock(MakeClockPlan(8'000'000));
    EXPECT_EQ(t.psc, 999u);
    EXPECT_EQ(t.status, proto::kClockTimerMeasured);
  }
}

TEST(Peripherals, UsartTimersSysTickAndPinsGetTheReferenceValues) {
  FakeStm32 f;
  const ClockPlan plan = MakeClockPlan(8'000'000);
  InitPins();
  InitUsart1(plan);
  InitTimers(83, 0xFFFF'0000u);
  InitSysTick(plan);
  InitInterrupts();
  using namespace stm32;
  EXPECT_EQ(f.Peek(kUsartBrr), 0x2D9u);   // 45.5625 as mantissa << 4 | fraction
  EXPECT_EQ(f.Peek(kUsartCr1), 0x202Cu);  // UE 13, RXNEIE 5, TE 3, RE 2
  for (uint32_t tim : {kTim2, kTim3, kTim4, kTim5}) EXPECT_EQ(f.Peek(tim + kTimPsc), 83u);
  EXPECT_EQ(f.Peek(kTim2 + kTimArr), 0xFFFFFFFFu);
  EXPECT_EQ(f.Peek(kTim5 + kTimArr), 0xFFFFFFFFu);
  EXPECT_EQ(f.Peek(kTim3 + kTimArr), 0xFFFFu);
  EXPECT_EQ(f.Peek(kTim2 + kTimCnt), 0xFFFF'0000u);  // the preset count
  EXPECT_EQ(f.Peek(kTim3 + kTimCnt), 0x0000u);       // its low 16 bits
  // Master / slaves (18.4.2-3): TIM2 MMS = 001 (enable -> TRGO); TIM3, TIM4 TS = 001 (ITR1 =
  // TIM2), TIM5 TS = 000 (ITR0 = TIM2); SMS = 110 (trigger mode).
  EXPECT_EQ(f.Peek(kTim2 + kTimCr2), 0x10u);
  EXPECT_EQ(f.Peek(kTim3 + kTimSmcr), 0x16u);
  EXPECT_EQ(f.Peek(kTim4 + kTimSmcr), 0x16u);
  EXPECT_EQ(f.Peek(kTim5 + kTimSmcr), 0x06u);
  EXPECT_EQ(f.writes().back().address, kNvicIser0 + 4);  // the interrupts last
  EXPECT_LT(f.FirstWrite(kTim5 + kTimSmcr, 6), f.FirstWrite(kTim2 + kTimCr1, 1))
      << "slaves wait for the master's start";
  // Outputs forced low (OCxM = 100 in both channels of each CCMR), all four enabled.
  EXPECT_EQ(f.Peek(kTim5 + kTimCcmr1), 0x4040u);
  EXPECT_EQ(f.Peek(kTim2 + kTimCcer), 0x1111u);
  // Inputs: CCxS = 01, ICxF = 0011; captures disabled until a run starts.
  EXPECT_EQ(f.Peek(kTim3 + kTimCcmr2), 0x3131u);
  EXPECT_EQ(f.Peek(kTim3 + kTimCcer), 0u);
  EXPECT_EQ(f.Peek(kSysTickRvr), 167'999u);
  EXPECT_EQ(f.Peek(kSysTickCsr), 7u);  // core clock, interrupt, enable
  // Pins: PA0-3 AF (MODER 10 each), AF2; PA9 / PA10 AF7; PA15 AF1; PC6-9 AF2; PB3 AF1.
  EXPECT_EQ(f.Peek(kGpioA + kGpioModer) & 0xFF, 0xAAu);
  EXPECT_EQ(f.Peek(kGpioA + kGpioAfrl) & 0xFFFF, 0x2222u);
  EXPECT_EQ(f.Peek(kGpioA + kGpioAfrh), 0x10000770u);
  EXPECT_EQ(f.Peek(kGpioC + kGpioAfrl) >> 24, 0x22u);
  EXPECT_EQ(f.Peek(kGpioC + kGpioAfrh) & 0xFF, 0x22u);
  EXPECT_EQ((f.Peek(kGpioB + kGpioAfrl) >> 12) & 0xF, 1u);
  // Priorities (one byte per irq): TIM2 (28) 0, TIM3 (29) 0x10, USART1 (37) 0x20, TIM5 (50) 0.
  EXPECT_EQ(f.Peek(kNvicIpr0 + 28) & 0xFF, 0x00u);
  EXPECT_EQ((f.Peek(kNvicIpr0 + 28) >> 8) & 0xFF, 0x10u);
  EXPECT_EQ((f.Peek(kNvicIpr0 + 36) >> 8) & 0xFF, 0x20u);
  EXPECT_EQ((f.Peek(kNvicIpr0 + 48) >> 16) & 0xFF, 0x00u);
  // ISER is write-1-to-set: TIM5 (50) and USART1 (37) in ISER1, TIM2-4 (28-30) in ISER0.
  EXPECT_EQ(f.ValuesWritten(kNvicIser0 + 4),
            (std::vector<uint32_t>{1u << (50 - 32), 1u << (37 - 32)}));
  EXPECT_EQ(f.ValuesWritten(kNvicIser0), (std::vector<uint32_t>{1u << 28, 1u << 29, 1u << 30}));
}

}  // namespace
}  // namespace rigcal::board
