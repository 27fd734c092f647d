// SPDX-License-Identifier: Apache-2.0
#pragma once
// CounterExtension: a free-running 32-bit hardware count (the board's µs timer, TIM2) extended to
// 64 bits in software, so MCU time never wraps (a 32-bit µs count wraps every 71.6 minutes: the
// bug VersaVIS had, its issue #37).
//
// Extend(count) must see the count at least once per 2^32 ticks (the main loop does, every
// millisecond); between two calls the count may wrap at most once. The first call's count is
// taken as is (a counter preset near 2^32 extends to just below 2^32, then past it).
// Freestanding; not thread-safe (the main loop owns it; interrupts work on 32-bit differences).

#include <cstdint>

namespace rigcal::trigger_core {

class CounterExtension {
 public:
  uint64_t Extend(uint32_t count) {
    if (count < last_count_) high_ += uint64_t{1} << 32;  // wrapped since the last call
    last_count_ = count;
    return high_ | count;
  }
  uint32_t wraps() const { return static_cast<uint32_t>(high_ >> 32); }

 private:
  uint32_t last_count_ = 0;
  uint64_t high_ = 0;
};

// The 64-bit time of a 32-bit count `count32` that lies within 2^31 ticks of `reference_us`
// (a capture or compare value near a known 64-bit time): the nearest 64-bit time whose low word
// is `count32`. Interrupts use it with the last edge's time as the reference.
constexpr uint64_t NearestTime(uint64_t reference_us, uint32_t count32) {
  const int32_t delta = static_cast<int32_t>(count32 - static_cast<uint32_t>(reference_us));
  return reference_us + static_cast<uint64_t>(static_cast<int64_t>(delta));
}

}  // namespace rigcal::trigger_core
