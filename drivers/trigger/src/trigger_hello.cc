// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/trigger_hello.h"

#include <vector>

namespace rigcal::trigger {

using trigger_proto::MessageType;

Expected<TriggerHelloInfo> QueryTriggerHello(TriggerLink* link, int timeout_ms) {
  const int64_t sent_ns = link->stream().NowNs();
  const int64_t deadline = sent_ns + int64_t{timeout_ms} * 1'000'000;
  std::vector<TriggerEvent> events;
  trigger_proto::Message get_info;
  get_info.type = MessageType::kGetInfo;
  Status answered = link->Command(get_info, timeout_ms, &events);
  while (true) {
    for (const TriggerEvent& e : events) {
      if (e.message.type == MessageType::kHello)
        return TriggerHelloInfo{e.message.hello, e.rx_ns - sent_ns};
    }
    events.clear();
    if (link->other_version() != 0) {
      return Error{"the trigger generator speaks protocol version " +
                   std::to_string(link->other_version()) + ", this host version " +
                   std::to_string(trigger_proto::kProtocolVersion) +
                   ": flash the firmware built with this release (make flash)"};
    }
    if (!answered.ok() || link->stream().NowNs() >= deadline) break;
    if (Status s = link->Poll(20, &events); !s.ok()) return Error{s.message()};
  }
  if (!answered.ok()) return Error{answered.message()};
  return Error{"no Hello within " + std::to_string(timeout_ms) + " ms after GetInfo's Ack"};
}

std::string DescribeClockStatus(uint8_t status, uint8_t hse_mhz) {
  const std::string crystal = std::to_string(hse_mhz) + " MHz crystal";
  if (status == 0)
    return "crystal " + std::to_string(hse_mhz) + " MHz -> PLL 168 MHz, timers as configured";
  std::string out;
  auto add = [&out](const std::string& s) { out += (out.empty() ? "" : "; ") + s; };
  if (status & trigger_proto::kClockHseFallback) {
    add("HSE (" + crystal + ") did not start: PLL from the internal 16 MHz RC, MCU time +-1 %");
  }
  if (status & trigger_proto::kClockPllFailed) {
    add("PLL not locked or not selected: rates may be wrong (an emulator without an RCC model)");
  }
  if (status & trigger_proto::kClockTimerMeasured) {
    add("timer clock differs from the configured 84 MHz: prescaler from its measurement");
  }
  if (status & trigger_proto::kClockTestImage) add("TEST IMAGE (counter preset near 2^32)");
  return out;
}

}  // namespace rigcal::trigger
