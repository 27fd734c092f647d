#include "board.h"

namespace rigcal::board {
namespace {

template <typename T = uint32_t>
volatile T& Reg(uint32_t address) {
  return *reinterpret_cast<volatile T*>(address);
}

// Core peripherals.
constexpr uint32_t kSysTickCsr = 0xE000E010;
constexpr uint32_t kSysTickRvr = 0xE000E014;
constexpr uint32_t kSysTickCvr = 0xE000E018;
constexpr uint32_t kNvicIser1 = 0xE000E104;
constexpr uint32_t kCpacr = 0xE000ED88;
// STM32F405 peripherals.
constexpr uint32_t kRccAhb1Enr = 0x40023830;
constexpr uint32_t kRccApb1Enr = 0x40023840;
constexpr uint32_t kRccApb2Enr = 0x40023844;
// TIM2: the 32-bit µs counter. Its input clock is 84 MHz on a real F405 (APB1 x 2); QEMU 7.2's
// netduinoplus2 clocks it at a fixed 1 GHz, hence the build option (CMake TRIGGER_TIMER_CLOCK_HZ).
#ifndef RIGCAL_TIMER_CLOCK_HZ
#define RIGCAL_TIMER_CLOCK_HZ 84000000u
#endif
constexpr uint32_t kTimerClockHz = RIGCAL_TIMER_CLOCK_HZ;
constexpr uint32_t kTim2 = 0x40000000;
constexpr uint32_t kTimCr1 = kTim2 + 0x00;
constexpr uint32_t kTimEgr = kTim2 + 0x14;
constexpr uint32_t kTimCnt = kTim2 + 0x24;
constexpr uint32_t kTimPsc = kTim2 + 0x28;
constexpr uint32_t kTimArr = kTim2 + 0x2C;
constexpr uint32_t kGpioE = 0x40021000;
constexpr uint32_t kUsart1 = 0x40011000;
constexpr uint32_t kUsartSr = kUsart1 + 0x00;
constexpr uint32_t kUsartDr = kUsart1 + 0x04;
constexpr uint32_t kUsartBrr = kUsart1 + 0x08;
constexpr uint32_t kUsartCr1 = kUsart1 + 0x0C;
constexpr uint32_t kSrRxne = 1u << 5;
constexpr uint32_t kSrTxe = 1u << 7;
constexpr uint32_t kSrOre = 1u << 3;
constexpr int kUsart1Irq = 37;

constexpr uint32_t kTicksPerMs = kCoreClockHz / 1000;

// The 64-bit extension of TIM2's count (NowUs runs in the main loop only, which wakes at least
// every millisecond: the 32-bit count wraps every 71 minutes).
uint32_t g_last_count = 0;
uint64_t g_high = 0;

// Received bytes: the USART1 interrupt writes rx_head, the main loop rx_tail.
constexpr uint32_t kRxSize = 256;
volatile uint8_t g_rx[kRxSize];
volatile uint32_t g_rx_head = 0;
volatile uint32_t g_rx_tail = 0;
volatile uint32_t g_rx_overruns = 0;

}  // namespace

void Init() {
  Reg(kCpacr) = Reg(kCpacr) | (0xFu << 20);         // FPU: full access to CP10 and CP11
  Reg(kRccAhb1Enr) = Reg(kRccAhb1Enr) | (1u << 4);  // GPIOE clock
  Reg(kRccApb2Enr) = Reg(kRccApb2Enr) | (1u << 4);  // USART1 clock
  Reg(kGpioE + 0x00) = 0x5555;                      // MODER: PE0..PE7 outputs
  Reg(kGpioE + 0x18) = 0xFFu << 16;                 // BSRR: all low
  // USART1 at 115200 baud from the 84 MHz APB2 clock (BRR = 84e6 / 115200 = 45.5625 = 45 + 9/16).
  Reg(kUsartBrr) = (45u << 4) | 9u;
  Reg(kUsartCr1) = (1u << 13) | (1u << 5) | (1u << 3) | (1u << 2);  // UE, RXNEIE, TE, RE
  Reg(kNvicIser1) = 1u << (kUsart1Irq - 32);
  Reg(kRccApb1Enr) = Reg(kRccApb1Enr) | 1u;      // TIM2 clock
  Reg(kTimPsc) = kTimerClockHz / 1'000'000 - 1;  // 1 MHz
  Reg(kTimArr) = 0xFFFFFFFFu;
  Reg(kTimEgr) = 1;  // load the prescaler
  Reg(kTimCnt) = 0;
  Reg(kTimCr1) = 1;  // count
  // SysTick only wakes the main loop every millisecond (its interrupts are not counted for the
  // time: QEMU loses some when the host is busy, TIM2's count follows the host clock).
  Reg(kSysTickRvr) = kTicksPerMs - 1;
  Reg(kSysTickCvr) = 0;
  Reg(kSysTickCsr) = 0x7;  // processor clock, interrupt, enable
}

uint64_t NowUs() {
  const uint32_t count = Reg(kTimCnt);
  if (count < g_last_count) g_high += uint64_t{1} << 32;
  g_last_count = count;
  return g_high | count;
}

bool ReadByte(uint8_t* byte) {
  const uint32_t tail = g_rx_tail;
  if (tail == g_rx_head) return false;
  *byte = g_rx[tail % kRxSize];
  g_rx_tail = tail + 1;
  return true;
}

bool CanWrite() { return (Reg(kUsartSr) & kSrTxe) != 0; }

void WriteByte(uint8_t byte) {
  while (!CanWrite()) {
  }
  Reg(kUsartDr) = byte;
}

void SetLines(uint8_t high_mask) {
  // BSRR: low half sets, high half resets; one write changes all eight lines at once.
  Reg(kGpioE + 0x18) = static_cast<uint32_t>(high_mask) |
                       (static_cast<uint32_t>(static_cast<uint8_t>(~high_mask)) << 16);
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

// Interrupt handlers (named in the vector table of startup.cc).
extern "C" void SysTick_Handler() {}  // wakes WaitForInterrupt

extern "C" void USART1_IRQHandler() {
  using namespace rigcal::board;
  const uint32_t sr = Reg(kUsartSr);
  if (sr & (kSrRxne | kSrOre)) {
    const uint8_t byte = static_cast<uint8_t>(Reg(kUsartDr));  // also clears RXNE / ORE
    const uint32_t head = g_rx_head;
    if (head - g_rx_tail < kRxSize) {
      g_rx[head % kRxSize] = byte;
      g_rx_head = head + 1;
    } else {
      g_rx_overruns = g_rx_overruns + 1;
    }
  }
}
