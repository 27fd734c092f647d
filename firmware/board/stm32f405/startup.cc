// SPDX-License-Identifier: Apache-2.0
// Reset and the vector table of the STM32F405: copies .data, clears .bss, enables the FPU, runs
// the static constructors (.init_array), calls main. Faults end the program through
// semihosting with a failure code, so a test sees a crash as QEMU exiting with 1.
#include <cstdint>

#include "board.h"

extern "C" {
extern uint32_t _sidata, _sdata, _edata, _sbss, _ebss, _estack;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
void Reset_Handler();
void SysTick_Handler();
void USART1_IRQHandler();
void TIM2_IRQHandler();
void TIM3_IRQHandler();
void TIM4_IRQHandler();
void TIM5_IRQHandler();

void Fault_Handler() { rigcal::board::Exit(false); }
void Default_Handler() { rigcal::board::Exit(false); }
// Called for a pure virtual function without an override (never, unless memory is corrupt).
void __cxa_pure_virtual() { rigcal::board::Exit(false); }

void Reset_Handler() {
  for (uint32_t *src = &_sidata, *dst = &_sdata; dst < &_edata;) *dst++ = *src++;
  for (uint32_t* dst = &_sbss; dst < &_ebss;) *dst++ = 0;
  *reinterpret_cast<volatile uint32_t*>(0xE000ED88) |= 0xFu << 20;  // FPU before any float
  for (auto** f = __init_array_start; f < __init_array_end; ++f) (*f)();
  main();
  rigcal::board::Exit(true);
}
}

namespace {
using Handler = void (*)();
constexpr int kIrqs = 82;
struct VectorTable {
  uint32_t* stack;
  Handler core[15];
  Handler irq[kIrqs];
};

constexpr VectorTable MakeTable() {
  VectorTable t{&_estack, {}, {}};
  t.core[0] = Reset_Handler;
  for (int i = 1; i < 15; ++i) t.core[i] = Default_Handler;
  t.core[1] = Default_Handler;                       // NMI
  t.core[2] = Fault_Handler;                         // HardFault
  t.core[3] = Fault_Handler;                         // MemManage
  t.core[4] = Fault_Handler;                         // BusFault
  t.core[5] = Fault_Handler;                         // UsageFault
  for (int i = 6; i < 10; ++i) t.core[i] = nullptr;  // reserved
  t.core[12] = nullptr;                              // reserved
  t.core[14] = SysTick_Handler;
  for (int i = 0; i < kIrqs; ++i) t.irq[i] = Default_Handler;
  t.irq[28] = TIM2_IRQHandler;
  t.irq[29] = TIM3_IRQHandler;
  t.irq[30] = TIM4_IRQHandler;
  t.irq[50] = TIM5_IRQHandler;
  t.irq[37] = USART1_IRQHandler;
  return t;
}
}  // namespace

__attribute__((section(".isr_vector"), used)) const VectorTable g_vectors = MakeTable();
