// The trigger generator's main loop on the STM32F405: the firmware core (TriggerApp) fed with
// the SysTick time and USART1's bytes; its frames go out on USART1, its lines on GPIOE.
// Between events the core sleeps (WFI) when the next one is more than 1.2 ms away, and polls
// otherwise, so edges are raised within a few µs of their time on a real MCU and QEMU does not
// spin a host core between ticks.
#include "board.h"
#include "rigcal/trigger_core/trigger_app.h"

namespace {

class GpioLines : public rigcal::trigger_core::LineDriver {
 public:
  void SetLines(uint8_t high_mask) override { rigcal::board::SetLines(high_mask); }
};

GpioLines g_lines;
rigcal::trigger_core::TriggerApp g_app(&g_lines);

}  // namespace

int main() {
  rigcal::board::Init();
  g_app.Boot(rigcal::board::NowUs());
  while (true) {
    const uint64_t now = rigcal::board::NowUs();
    uint8_t byte;
    while (rigcal::board::ReadByte(&byte)) g_app.OnRxByte(byte, now);
    g_app.Poll(now);
    while (rigcal::board::CanWrite() && g_app.PopTx(&byte)) rigcal::board::WriteByte(byte);
    const uint64_t next = g_app.scheduler().NextEventUs();
    if (g_app.tx_pending() == 0 && (next == UINT64_MAX || next > rigcal::board::NowUs() + 1'200)) {
      rigcal::board::WaitForInterrupt();
    }
  }
}
