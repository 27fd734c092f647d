#pragma once
// The STM32F405 board port of the trigger generator (netduinoplus2 under QEMU, or a real board
// with the trigger lines on PE0..PE7 and the host link on USART1 (PA9 TX, PA10 RX)).
//   time base   TIM2 counting µs (32 bits, extended to 64 in software); SysTick at 1 kHz wakes
//               the main loop
//   serial      USART1, received bytes buffered by its interrupt, sent by polling TXE
//   lines       GPIOE ODR bits 0..7 through BSRR (QEMU ignores the writes)
// Everything here runs on the MCU only; the logic lives in firmware/core.

#include <cstdint>

namespace rigcal::board {

inline constexpr uint32_t kCoreClockHz = 168'000'000;

void Init();
// Microseconds since Init (64 bits: no wrap in practice). Main loop only (not interrupts).
uint64_t NowUs();
// Next received byte; false when none is buffered.
bool ReadByte(uint8_t* byte);
// True when the UART can take a byte now; WriteByte then does not block.
bool CanWrite();
void WriteByte(uint8_t byte);
void SetLines(uint8_t high_mask);
// Sleeps until the next interrupt (the 1 kHz SysTick or a received byte).
void WaitForInterrupt();
// Received bytes lost because the firmware did not read them in time.
uint32_t RxOverruns();
// Ends the program through semihosting (QEMU exits with 0 for success, 1 otherwise); on a
// board without a debugger it stops in a breakpoint loop.
[[noreturn]] void Exit(bool success);

}  // namespace rigcal::board
