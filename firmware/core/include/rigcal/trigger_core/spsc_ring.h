// SPDX-License-Identifier: Apache-2.0
#pragma once
// SpscRing: a fixed ring of N values from one producer (an interrupt) to one consumer (the main
// loop). Push and Pop never block; a full ring refuses the value (the caller counts it). The
// indices are atomics with release / acquire order, so on the MCU the consumer sees a value
// whole once its index moved. Freestanding.

#include <atomic>
#include <cstdint>

namespace rigcal::trigger_core {

template <typename T, uint32_t N>
class SpscRing {
  static_assert(N > 0 && (N & (N - 1)) == 0, "N must be a power of two");

 public:
  // Producer side.
  bool Push(const T& value) {
    const uint32_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_.load(std::memory_order_acquire) >= N) return false;
    items_[head % N] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }
  // Consumer side: the oldest value, without removing it (null when empty).
  const T* Front() const {
    const uint32_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_.load(std::memory_order_acquire)) return nullptr;
    return &items_[tail % N];
  }
  void PopFront() {
    tail_.store(tail_.load(std::memory_order_relaxed) + 1, std::memory_order_release);
  }
  // Either side (main loop while the producer is quiet: Start).
  void Clear() { tail_.store(head_.load(std::memory_order_acquire), std::memory_order_release); }

 private:
  T items_[N] = {};
  std::atomic<uint32_t> head_{0};
  std::atomic<uint32_t> tail_{0};
};

}  // namespace rigcal::trigger_core
