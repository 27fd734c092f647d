// SPDX-License-Identifier: Apache-2.0
#pragma once
// The shared time base of a realtime simulated rig. Private to rigcal_sim.

#include <chrono>
#include <cstdint>
#include <functional>
#include <utility>

#include "rigcal/base/thread_annotations.h"

namespace rigcal::sim::internal {

// CLOCK_MONOTONIC (std::chrono::steady_clock on Linux), nanoseconds.
inline int64_t MonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The shared time base of a realtime rig: CLOCK_MONOTONIC (std::chrono::steady_clock on
// Linux) at the first Grab of any of its devices, a given epoch, or a given clock (the host time
// of a time since frame 0, asked at every frame: a trigger generator's, see StartOn).
struct RigClock {
  using HostNsSince = std::function<int64_t(int64_t since_frame0_ns)>;

  Mutex mutex;
  bool started RIGCAL_GUARDED_BY(mutex) = false;
  int64_t epoch_ns RIGCAL_GUARDED_BY(mutex) = 0;
  HostNsSince host_ns_since RIGCAL_GUARDED_BY(mutex);  // empty: epoch_ns + the time

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
  void StartOn(HostNsSince clock) RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    if (!started) {
      started = true;
      epoch_ns = clock(0);
      host_ns_since = std::move(clock);
    }
  }
  int64_t Epoch() RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    return epoch_ns;
  }
  // Host time of `since_frame0_ns` after frame 0 (started).
  int64_t HostNs(int64_t since_frame0_ns) RIGCAL_EXCLUDES(mutex) {
    HostNsSince clock;
    int64_t epoch = 0;
    {
      MutexLock lock(mutex);
      clock = host_ns_since;
      epoch = epoch_ns;
    }
    return clock ? clock(since_frame0_ns) : epoch + since_frame0_ns;
  }
};

}  // namespace rigcal::sim::internal
