// SPDX-License-Identifier: Apache-2.0
#pragma once
// Which timer channel and pin each trigger line and exposure input uses on an STM32F405RG
// (LQFP64: ports A, B, C; docs/firmware.md has the same table with the wiring). Every pin is
// bonded out on the 64-pin part; alternate functions per the F405 datasheet (DS8626, table 9).
//
//   line  trigger out (output compare)     exposure in (input capture)
//   0     PA0   TIM5_CH1  AF2               PC6  TIM3_CH1  AF2
//   1     PA1   TIM5_CH2  AF2               PC7  TIM3_CH2  AF2
//   2     PA2   TIM5_CH3  AF2               PC8  TIM3_CH3  AF2
//   3     PA3   TIM5_CH4  AF2               PC9  TIM3_CH4  AF2
//   4     PA15  TIM2_CH1  AF1               PB6  TIM4_CH1  AF2
//   5     PB3   TIM2_CH2  AF1               PB7  TIM4_CH2  AF2
//   6     PB10  TIM2_CH3  AF1               PB8  TIM4_CH3  AF2
//   7     PB11  TIM2_CH4  AF1               PB9  TIM4_CH4  AF2
//   host link: USART1 PA9 (TX) / PA10 (RX), AF7.  Debug: SWD on PA13 / PA14 (PA15 and PB3 are
//   JTDI / SWO after reset: the firmware takes them over, SWD keeps working).
//
// TIM2 (32-bit) counts the µs and is the master; TIM5 (32-bit), TIM3 and TIM4 (16-bit) start
// on its trigger output with the same prescaler, so every channel compares or captures the same
// count (TIM3 / TIM4: its low 16 bits).

#include <cstdint>

#include "stm32f405_map.h"

namespace rigcal::board {

struct Pin {
  uint32_t port;  // GPIOx base
  uint32_t pin;   // 0..15
  uint32_t af;    // alternate function number
};

struct LinePins {
  uint32_t out_timer;    // TIMx base of the output-compare channel
  uint32_t out_channel;  // 1..4
  Pin out;
  uint32_t in_timer;    // TIMx base of the input-capture channel
  uint32_t in_channel;  // 1..4
  Pin in;
};

inline constexpr LinePins kLinePins[8] = {
    {stm32::kTim5, 1, {stm32::kGpioA, 0, 2}, stm32::kTim3, 1, {stm32::kGpioC, 6, 2}},
    {stm32::kTim5, 2, {stm32::kGpioA, 1, 2}, stm32::kTim3, 2, {stm32::kGpioC, 7, 2}},
    {stm32::kTim5, 3, {stm32::kGpioA, 2, 2}, stm32::kTim3, 3, {stm32::kGpioC, 8, 2}},
    {stm32::kTim5, 4, {stm32::kGpioA, 3, 2}, stm32::kTim3, 4, {stm32::kGpioC, 9, 2}},
    {stm32::kTim2, 1, {stm32::kGpioA, 15, 1}, stm32::kTim4, 1, {stm32::kGpioB, 6, 2}},
    {stm32::kTim2, 2, {stm32::kGpioB, 3, 1}, stm32::kTim4, 2, {stm32::kGpioB, 7, 2}},
    {stm32::kTim2, 3, {stm32::kGpioB, 10, 1}, stm32::kTim4, 3, {stm32::kGpioB, 8, 2}},
    {stm32::kTim2, 4, {stm32::kGpioB, 11, 1}, stm32::kTim4, 4, {stm32::kGpioB, 9, 2}},
};
inline constexpr Pin kUsart1Tx = {stm32::kGpioA, 9, 7};
inline constexpr Pin kUsart1Rx = {stm32::kGpioA, 10, 7};

}  // namespace rigcal::board
