// SPDX-License-Identifier: Apache-2.0
// The trigger generator's main loop on the STM32F405: the firmware core (TriggerApp) fed with
// TIM2's µs time and USART1's bytes; its frames go out on USART1. The lines are timer channels:
// their interrupts (below) arm each line's next edge, so no edge waits for this loop.
// Between events the loop sleeps (WFI) when nothing is due within 1.2 ms, and polls otherwise:
// on a board the timer interrupts wake it anyway; under QEMU, whose timers have no compare
// model, the loop itself makes the due edges (ServiceDueCompares) about when they are due.
#include "board.h"
#include "rigcal/trigger_core/trigger_app.h"
#include "stm32_line_timers.h"
#include "stm32f405_map.h"

namespace {

rigcal::board::Stm32LineTimers g_timers;
rigcal::trigger_core::TriggerApp g_app(&g_timers);

constexpr uint64_t kPollWindowUs = 1'200;

bool SomethingDueSoon(uint64_t now_us) {
  const uint64_t report_us = g_app.scheduler().NextReportUs();
  return g_app.tx_pending() != 0 || report_us <= now_us + kPollWindowUs ||
         g_timers.UsToNextEdge(rigcal::board::Now32()) <= kPollWindowUs;
}

}  // namespace

extern "C" void TIM2_IRQHandler() {
  g_timers.ServiceCompareInterrupt(rigcal::board::stm32::kTim2, &g_app);
}
extern "C" void TIM5_IRQHandler() {
  g_timers.ServiceCompareInterrupt(rigcal::board::stm32::kTim5, &g_app);
}
extern "C" void TIM3_IRQHandler() {
  g_timers.ServiceCaptureInterrupt(rigcal::board::stm32::kTim3, &g_app);
}
extern "C" void TIM4_IRQHandler() {
  g_timers.ServiceCaptureInterrupt(rigcal::board::stm32::kTim4, &g_app);
}

int main() {
  const rigcal::trigger_core::BoardInfo info = rigcal::board::Init();
  g_app.Boot(rigcal::board::NowUs(), info);
  while (true) {
    const uint64_t now = rigcal::board::NowUs();
    uint8_t byte;
    while (rigcal::board::ReadByte(&byte)) g_app.OnRxByte(byte, now);
    rigcal::board::DisableInterrupts();
    g_timers.ServiceDueCompares(&g_app);
    rigcal::board::EnableInterrupts();
    g_app.Poll(now);
    while (rigcal::board::CanWrite() && g_app.PopTx(&byte)) rigcal::board::WriteByte(byte);
    if (!SomethingDueSoon(rigcal::board::NowUs())) rigcal::board::WaitForInterrupt();
  }
}
