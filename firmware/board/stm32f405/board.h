// SPDX-License-Identifier: Apache-2.0
#pragma once
// The STM32F405 board port of the trigger generator (a real board, or netduinoplus2 under QEMU):
//   clocks      clock_tree.h: HSE (TRIGGER_HSE_HZ) -> PLL 168 MHz, HSI fallback; clock_config.h
//   time base   TIM2 counting µs (32 bits, extended to 64 in software: CounterExtension)
//   lines       timer output compares, exposure inputs timer captures (pinout.h,
//               stm32_line_timers.h); SysTick at 1 kHz wakes the main loop
//   serial      USART1, received bytes buffered by its interrupt, sent by polling TXE
// Everything here runs on the MCU only; the logic lives in firmware/core, the register-level
// start-up in clock_tree.cc / peripherals.cc (also built on the host for the register tests).

#include <cstdint>

#include "rigcal/trigger_core/trigger_app.h"

namespace rigcal::board {

// Clocks, timer-clock check, pins, USART1, timers, SysTick, interrupts. Returns the Hello's
// clock status and crystal.
trigger_core::BoardInfo Init();
// Microseconds since the timers started (64 bits: no wrap in practice; a test image starts near
// 2^32). Main loop only (not interrupts).
uint64_t NowUs();
// TIM2's count now (the low 32 bits of NowUs).
uint32_t Now32();
// Next received byte; false when none is buffered.
bool ReadByte(uint8_t* byte);
// True when the UART can take a byte now; WriteByte then does not block.
bool CanWrite();
void WriteByte(uint8_t byte);
// Sleeps until the next interrupt (SysTick, a timer, a received byte).
void WaitForInterrupt();
inline void DisableInterrupts() { asm volatile("cpsid i" ::: "memory"); }
inline void EnableInterrupts() { asm volatile("cpsie i" ::: "memory"); }
// Received bytes lost because the firmware did not read them in time.
uint32_t RxOverruns();
// Ends the program through semihosting (QEMU exits with 0 for success, 1 otherwise); on a
// board without a debugger it stops in a breakpoint loop.
[[noreturn]] void Exit(bool success);

}  // namespace rigcal::board
