#pragma once
// The shared time base of a realtime simulated rig. Private to drivers/.

#include <chrono>
#include <cstdint>
#include <mutex>

namespace rigcal::drivers::internal {

// CLOCK_MONOTONIC (std::chrono::steady_clock on Linux), nanoseconds.
inline int64_t MonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The shared time base of a realtime rig: CLOCK_MONOTONIC (std::chrono::steady_clock on
// Linux) at the first Grab of any of its devices.
struct RigClock {
  std::mutex mutex;
  bool started = false;  // guarded by mutex
  int64_t epoch_ns = 0;  // guarded by mutex

  int64_t StartOnce() {
    std::lock_guard<std::mutex> lock(mutex);
    if (!started) {
      started = true;
      epoch_ns = MonotonicNs();
    }
    return epoch_ns;
  }
  int64_t Epoch() {
    std::lock_guard<std::mutex> lock(mutex);
    return epoch_ns;
  }
};

}  // namespace rigcal::drivers::internal
