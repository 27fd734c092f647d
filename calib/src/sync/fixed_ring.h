// SPDX-License-Identifier: Apache-2.0
#pragma once
// FixedRing: a FIFO over storage allocated once, for the sync buffer's per-camera rings and
// its ready queue, and the online glitch gate's rings of recent steps
// (motions/pose_glitch_gate.h). Not thread-safe: its owner guards it.

#include <cstddef>
#include <vector>

namespace rigcal {

// PushBack on a full ring is not allowed: the caller drops the oldest slot first (PopFront).
template <typename T>
class FixedRing {
 public:
  FixedRing(size_t capacity, const T& prototype) : slots_(capacity, prototype) {}

  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == slots_.size(); }
  T& operator[](size_t i) { return slots_[(head_ + i) % slots_.size()]; }
  const T& operator[](size_t i) const { return slots_[(head_ + i) % slots_.size()]; }
  T& front() { return slots_[head_]; }
  const T& front() const { return slots_[head_]; }

  // The slot after the newest one, now part of the ring (the caller fills it). The ring must
  // not be full.
  T& PushBack() {
    T& slot = slots_[(head_ + size_) % slots_.size()];
    ++size_;
    return slot;
  }
  void PopFront() {
    head_ = (head_ + 1) % slots_.size();
    --size_;
  }

 private:
  std::vector<T> slots_;
  size_t head_ = 0;
  size_t size_ = 0;
};

}  // namespace rigcal
