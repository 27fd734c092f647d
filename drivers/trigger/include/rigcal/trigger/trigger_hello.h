// SPDX-License-Identifier: Apache-2.0
#pragma once
// Asking a trigger generator who it is: GetInfo, answered by an Ack and a Hello (firmware
// version, lines, MCU time, and how its clocks came up: messages.h ClockStatusBit). The link check
// of `rigcal trigger --hello` and of a bench set-up (docs/firmware.md).
//
// Threads: the caller owns the link.

#include <cstdint>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/trigger/trigger_link.h"

namespace rigcal::trigger {

struct TriggerHelloInfo {
  trigger_proto::Hello hello;
  int64_t round_trip_ns = 0;  // GetInfo written -> Hello received (host clock)
};

// Sends GetInfo and waits up to `timeout_ms` for the Hello. Errors: no answer (names the
// timeout), the generator speaks another protocol version (names both versions: which side to
// update), the stream failed.
Expected<TriggerHelloInfo> QueryTriggerHello(TriggerLink* link, int timeout_ms);

// One line on the clock status: "crystal 8 MHz -> PLL 168 MHz" when it is 0, else each bit's
// meaning ("HSE (8 MHz crystal) did not start: PLL from the internal 16 MHz RC, +-1 %", ...).
std::string DescribeClockStatus(uint8_t clock_status, uint8_t hse_mhz);

}  // namespace rigcal::trigger
