// SPDX-License-Identifier: Apache-2.0
#include "board.h"

#include "clock_tree.h"
#include "peripherals.h"
#include "register_access.h"
#include "rigcal/trigger_core/counter_extension.h"
#include "stm32f405_map.h"

// A test image presets the µs counter (CMake TRIGGER_TEST_COUNTER_PRESET) to run across its wrap.
#ifdef RIGCAL_COUNTER_PRESET
#define RIGCAL_TEST_IMAGE 1
#else
#define RIGCAL_COUNTER_PRESET 0u
#define RIGCAL_TEST_IMAGE 0
#endif

namespace rigcal::board {
namespace {

using namespace stm32;
namespace proto = ::rigcal::trigger_protocol;

trigger_core::CounterExtension g_time;  // main loop only

// Received bytes: the USART1 interrupt writes rx_head, the main loop rx_tail.
constexpr uint32_t kRxSize = 256;
volatile uint8_t g_rx[kRxSize];
volatile uint32_t g_rx_head = 0;
volatile uint32_t g_rx_tail = 0;
volatile uint32_t g_rx_overruns = 0;

}  // namespace

trigger_core::BoardInfo Init() {
  uint8_t status = ConfigureClockTree(kClockPlan);
  const TimerClock timer = MeasureTimerClock(kClockPlan);
  status |= timer.status;
  if (RIGCAL_TEST_IMAGE) status |= proto::kClockTestImage;
  InitPins();
  InitUsart1(kClockPlan);
  InitTimers(timer.psc, RIGCAL_COUNTER_PRESET);
  InitSysTick(kClockPlan);
  InitInterrupts();
  return {status, static_cast<uint8_t>(kClockPlan.hse_hz / 1'000'000)};
}

uint32_t Now32() { return Read32(kTim2 + kTimCnt); }

uint64_t NowUs() { return g_time.Extend(Now32()); }

bool ReadByte(uint8_t* byte) {
  const uint32_t tail = g_rx_tail;
  if (tail == g_rx_head) return false;
  *byte = g_rx[tail % kRxSize];
  g_rx_tail = tail + 1;
  return true;
}

bool CanWrite() { return (Read32(kUsartSr) & kUsartSrTxe) != 0; }

void WriteByte(uint8_t byte) {
  while (!CanWrite()) {
  }
  Write32(kUsartDr, byte);
}

void WaitForInterrupt() { asm volatile("wfi"); }

uint32_t RxOverruns() { return g_rx_overruns; }

void Exit(bool success) {
  // Semihosting SYS_EXIT (0x18) with ADP_Stopped_ApplicationExit (0x20026) for success,
  // ADP_Stopped_RunTimeErrorUnknown (0x20023) otherwise.
  register uint32_t r0 asm("r0") = 0x18;
  register uint32_t r1 asm("r1") = success ? 0x20026 : 0x20023;
  asm volatile("bkpt 0xAB" : : "r"(r0), "r"(r1) : "memory");
  while (true) {
  }
}

}  // namespace rigcal::board

extern "C" void SysTick_Handler() {}  // wakes WaitForInterrupt

extern "C" void USART1_IRQHandler() {
  using namespace rigcal::board;
  const uint32_t sr = Read32(kUsartSr);
  if (sr & (kUsartSrRxne | kUsartSrOre)) {
    const uint8_t byte = static_cast<uint8_t>(Read32(kUsartDr));  // also clears RXNE / ORE
    const uint32_t head = g_rx_head;
    if (head - g_rx_tail < kRxSize) {
      g_rx[head % kRxSize] = byte;
      g_rx_head = head + 1;
    } else {
      g_rx_overruns = g_rx_overruns + 1;
    }
  }
}
