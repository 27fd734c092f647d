// SPDX-License-Identifier: Apache-2.0
#pragma once
// The shared time base of a realtime simulated rig. Private to rigcal_sim.

#include <chrono>
#include <cstdint>

#include "rigcal/base/thread_annotations.h"

namespace rigcal::sim::internal {

// CLOCK_MONOTONIC (std::chrono::steady_clock on Linux), nanoseconds.
inline int64_t MonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The shared time base of a realtime rig: CLOCK_MONOTONIC (std::chrono::steady_clock on
// Linux) at the first Grab of any of its devices.
struct RigClock {
  Mutex mutex;
  bool started RIGCAL_GUARDED_BY(mutex) = false;
  int64_t epoch_ns RIGCAL_GUARDED_BY(mutex) = 0;

  int64_t StartOnce() RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    if (!started) {
      started = true;
      epoch_ns = MonotonicNs();
    }
    return epoch_ns;
  }
  int64_t StartAt(int64_t t_ns) RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    if (!started) {
      started = true;
      epoch_ns = t_ns;
    }
    return epoch_ns;
  }
  int64_t Epoch() RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    return epoch_ns;
  }
};

}  // namespace rigcal::sim::internal
