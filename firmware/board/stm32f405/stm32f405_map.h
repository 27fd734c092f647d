// SPDX-License-Identifier: Apache-2.0
#pragma once
// The STM32F405 registers the trigger firmware uses: addresses and fields as RM0090 (the
// STM32F405/415/407/417 reference manual, rev. 19) and PM0214 (Cortex-M4 core peripherals)
// define them. Section numbers name where each one is described.

#include <cstdint>

namespace rigcal::board::stm32 {

// Cortex-M4 core (PM0214 4.5 SysTick, 4.3 NVIC, 4.6 CPACR).
inline constexpr uint32_t kSysTickCsr = 0xE000E010;
inline constexpr uint32_t kSysTickRvr = 0xE000E014;
inline constexpr uint32_t kSysTickCvr = 0xE000E018;
inline constexpr uint32_t kSysTickCsrEnable = 1u << 0;
inline constexpr uint32_t kSysTickCsrTickInt = 1u << 1;
inline constexpr uint32_t kSysTickCsrCoreClock = 1u << 2;
inline constexpr uint32_t kNvicIser0 = 0xE000E100;  // + 4 * (irq / 32)
inline constexpr uint32_t kNvicIpr0 = 0xE000E400;   // one byte per irq
inline constexpr uint32_t kCpacr = 0xE000ED88;

// RCC (RM0090 7.3).
inline constexpr uint32_t kRcc = 0x40023800;
inline constexpr uint32_t kRccCr = kRcc + 0x00;
inline constexpr uint32_t kRccPllCfgr = kRcc + 0x04;
inline constexpr uint32_t kRccCfgr = kRcc + 0x08;
inline constexpr uint32_t kRccAhb1Enr = kRcc + 0x30;
inline constexpr uint32_t kRccApb1Enr = kRcc + 0x40;
inline constexpr uint32_t kRccApb2Enr = kRcc + 0x44;
inline constexpr uint32_t kRccCrHseOn = 1u << 16;
inline constexpr uint32_t kRccCrHseRdy = 1u << 17;
inline constexpr uint32_t kRccCrPllOn = 1u << 24;
inline constexpr uint32_t kRccCrPllRdy = 1u << 25;
inline constexpr uint32_t kRccPllCfgrSrcHse = 1u << 22;
inline constexpr uint32_t kRccCfgrSwMask = 3u << 0;
inline constexpr uint32_t kRccCfgrSwPll = 2u << 0;
inline constexpr uint32_t kRccCfgrSwsMask = 3u << 2;
inline constexpr uint32_t kRccCfgrSwsPll = 2u << 2;
inline constexpr uint32_t kRccCfgrHpreDiv1 = 0u << 4;
inline constexpr uint32_t kRccCfgrPpre1Div4 = 5u << 10;
inline constexpr uint32_t kRccCfgrPpre2Div2 = 4u << 13;
inline constexpr uint32_t kRccAhb1GpioA = 1u << 0;
inline constexpr uint32_t kRccAhb1GpioB = 1u << 1;
inline constexpr uint32_t kRccAhb1GpioC = 1u << 2;
inline constexpr uint32_t kRccApb1Tim2 = 1u << 0;
inline constexpr uint32_t kRccApb1Tim3 = 1u << 1;
inline constexpr uint32_t kRccApb1Tim4 = 1u << 2;
inline constexpr uint32_t kRccApb1Tim5 = 1u << 3;
inline constexpr uint32_t kRccApb1Pwr = 1u << 28;
inline constexpr uint32_t kRccApb2Usart1 = 1u << 4;

// PWR (RM0090 5.4.1): VOS = scale 1, needed above 144 MHz.
inline constexpr uint32_t kPwrCr = 0x40007000;
inline constexpr uint32_t kPwrCrVos = 1u << 14;

// FLASH (RM0090 3.9.1).
inline constexpr uint32_t kFlashAcr = 0x40023C00;
inline constexpr uint32_t kFlashAcrLatencyMask = 7u << 0;
inline constexpr uint32_t kFlashAcrPrften = 1u << 8;
inline constexpr uint32_t kFlashAcrIcen = 1u << 9;
inline constexpr uint32_t kFlashAcrDcen = 1u << 10;

// GPIO (RM0090 8.4).
inline constexpr uint32_t kGpioA = 0x40020000;
inline constexpr uint32_t kGpioB = 0x40020400;
inline constexpr uint32_t kGpioC = 0x40020800;
inline constexpr uint32_t kGpioModer = 0x00;
inline constexpr uint32_t kGpioOspeedr = 0x08;
inline constexpr uint32_t kGpioIdr = 0x10;
inline constexpr uint32_t kGpioAfrl = 0x20;
inline constexpr uint32_t kGpioAfrh = 0x24;

// USART1 (RM0090 30.6).
inline constexpr uint32_t kUsart1 = 0x40011000;
inline constexpr uint32_t kUsartSr = kUsart1 + 0x00;
inline constexpr uint32_t kUsartDr = kUsart1 + 0x04;
inline constexpr uint32_t kUsartBrr = kUsart1 + 0x08;
inline constexpr uint32_t kUsartCr1 = kUsart1 + 0x0C;
inline constexpr uint32_t kUsartSrOre = 1u << 3;
inline constexpr uint32_t kUsartSrRxne = 1u << 5;
inline constexpr uint32_t kUsartSrTxe = 1u << 7;
inline constexpr uint32_t kUsartCr1Re = 1u << 2;
inline constexpr uint32_t kUsartCr1Te = 1u << 3;
inline constexpr uint32_t kUsartCr1Rxneie = 1u << 5;
inline constexpr uint32_t kUsartCr1Ue = 1u << 13;

// TIM2..TIM5 (RM0090 18.4): TIM2 and TIM5 32-bit, TIM3 and TIM4 16-bit, all on APB1.
inline constexpr uint32_t kTim2 = 0x40000000;
inline constexpr uint32_t kTim3 = 0x40000400;
inline constexpr uint32_t kTim4 = 0x40000800;
inline constexpr uint32_t kTim5 = 0x40000C00;
inline constexpr uint32_t kTimCr1 = 0x00;
inline constexpr uint32_t kTimCr2 = 0x04;
inline constexpr uint32_t kTimSmcr = 0x08;
inline constexpr uint32_t kTimDier = 0x0C;
inline constexpr uint32_t kTimSr = 0x10;
inline constexpr uint32_t kTimEgr = 0x14;
inline constexpr uint32_t kTimCcmr1 = 0x18;
inline constexpr uint32_t kTimCcmr2 = 0x1C;
inline constexpr uint32_t kTimCcer = 0x20;
inline constexpr uint32_t kTimCnt = 0x24;
inline constexpr uint32_t kTimPsc = 0x28;
inline constexpr uint32_t kTimArr = 0x2C;
inline constexpr uint32_t kTimCcr1 = 0x34;  // CCRn at 0x34 + 4 * (n - 1)
inline constexpr uint32_t kTimCr1Cen = 1u << 0;
inline constexpr uint32_t kTimCr2MmsEnable = 1u << 4;    // TRGO = counter enable
inline constexpr uint32_t kTimSmcrSmsTrigger = 6u << 0;  // the counter starts on TRGI
inline constexpr uint32_t kTimSmcrTsShift = 4;
inline constexpr uint32_t kTimEgrUg = 1u << 0;
// CCMR: per channel a byte (channels 1, 3 low, 2, 4 high): output OCxM at bits 6:4 of it,
// input CCxS at 1:0 and ICxF at 7:4.
inline constexpr uint32_t kOcmFrozen = 0;
inline constexpr uint32_t kOcmActiveOnMatch = 1;
inline constexpr uint32_t kOcmInactiveOnMatch = 2;
inline constexpr uint32_t kOcmForceInactive = 4;
inline constexpr uint32_t kOcmForceActive = 5;
inline constexpr uint32_t kCcsInputTi = 1;  // CCxS = 01: ICx on TIx
inline constexpr uint32_t kIcFilterN8 = 3;  // ICxF = 0011: fCK_INT, 8 samples
// CCER: per channel 4 bits: CCxE (0), CCxP (1), CCxNP (3).
inline constexpr uint32_t kCcerEnable = 1u << 0;
inline constexpr uint32_t kCcerFalling = 1u << 1;
// SR / DIER: CCxIF / CCxIE at bit x, CCxOF at bit 8 + x.
inline constexpr uint32_t kTimIrqTim2 = 28;
inline constexpr uint32_t kTimIrqTim3 = 29;
inline constexpr uint32_t kTimIrqTim4 = 30;
inline constexpr uint32_t kTimIrqTim5 = 50;
inline constexpr uint32_t kUsart1Irq = 37;

// Internal trigger inputs (RM0090 18.4.3, "TIMx internal trigger connection"): TIM2's TRGO is
// ITR1 of TIM3 and TIM4, ITR0 of TIM5.
inline constexpr uint32_t kTim3ItrTim2 = 1;
inline constexpr uint32_t kTim4ItrTim2 = 1;
inline constexpr uint32_t kTim5ItrTim2 = 0;

}  // namespace rigcal::board::stm32
