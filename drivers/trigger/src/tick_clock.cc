// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/tick_clock.h"

#include <algorithm>

namespace rigcal::trigger {

int64_t TickClock::HostNs(int64_t since_tick_ns) const {
  // The generator's µs; the nanoseconds below a µs are added on the host.
  const int64_t since_tick_us = since_tick_ns / 1000;
  const int64_t below_us_ns = since_tick_ns - since_tick_us * 1000;
  const int64_t mcu_us = std::max<int64_t>(0, static_cast<int64_t>(tick_mcu_us_) + since_tick_us);
  const std::optional<int64_t> mapped_ns = matcher_->MapMcuTime(static_cast<uint64_t>(mcu_us));
  MutexLock lock(mutex_);
  if (mapped_ns) {
    last_offset_ns_ = *mapped_ns - mcu_us * 1000;
    return *mapped_ns + below_us_ns;
  }
  const int64_t offset_ns = last_offset_ns_
                                ? *last_offset_ns_
                                : tick_host_ns_ - static_cast<int64_t>(tick_mcu_us_) * 1000;
  return mcu_us * 1000 + offset_ns + below_us_ns;
}

}  // namespace rigcal::trigger
