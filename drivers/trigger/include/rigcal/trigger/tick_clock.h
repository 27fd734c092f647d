// SPDX-License-Identifier: Apache-2.0
#pragma once
// TickClock: the host time of a source paced from a live trigger generator (a simulated rig or an
// image-folder replay that the generator "exposes"): time since a trigger tick runs on the
// generator's clock and is mapped to the host's (CLOCK_MONOTONIC) as the matcher's clock map is
// at each call. So the source's frames stay on the pulses when the map moves after the start (a
// restart after arrivals that were all late on a loaded host) and when the generator's crystal
// drifts (50 ppm is 5 ms, the matcher's default tolerance, after 100 s). While the map is not
// synced (after an MCU reset) the last mapping's offset is kept.
//
// Threads: HostNs from any thread (the cameras of a source share one TickClock).

#include <cstdint>
#include <optional>

#include "rigcal/base/thread_annotations.h"
#include "rigcal/trigger/trigger_matcher.h"

namespace rigcal::trigger {

class TickClock {
 public:
  // `matcher` outlives the clock; the tick is at `tick_mcu_us` on the generator's clock, mapped
  // to `tick_host_ns` when the source starts.
  TickClock(const TriggerMatcher* matcher, uint64_t tick_mcu_us, int64_t tick_host_ns)
      : matcher_(matcher), tick_mcu_us_(tick_mcu_us), tick_host_ns_(tick_host_ns) {}

  // Host time (ns) of `since_tick_ns` of the generator's time after the tick.
  int64_t HostNs(int64_t since_tick_ns) const RIGCAL_EXCLUDES(mutex_);

 private:
  const TriggerMatcher* matcher_;
  const uint64_t tick_mcu_us_;
  const int64_t tick_host_ns_;
  mutable Mutex mutex_;
  // Host ns - MCU µs * 1000 at the last mapped call.
  mutable std::optional<int64_t> last_offset_ns_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::trigger
