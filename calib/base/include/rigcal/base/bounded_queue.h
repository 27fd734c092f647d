// SPDX-License-Identifier: Apache-2.0
#pragma once
// BoundedQueue: a fixed-capacity multi-producer queue between pipeline threads. Push never
// blocks: when full, the oldest element is dropped and counted (capture must never wait for
// a slow consumer); PushWait waits for room instead (sources that can wait), PushWaitUntil for
// at most a deadline. Pop blocks until an element arrives or the queue is stopped.
//
// Threads: producers (capture threads) call Push/PushWait, consumers (VO threads) call
// Pop, any thread calls Stop and the counters. Every member is thread-safe: all state is
// guarded by mutex_; the queue owns no thread.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <optional>
#include <utility>

#include "rigcal/base/thread_annotations.h"

namespace rigcal {

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  // Appends `value`; drops the oldest element when full. Returns false when stopped (the
  // value is discarded). Any thread.
  bool Push(T value) RIGCAL_EXCLUDES(mutex_) {
    {
      MutexLock lock(mutex_);
      if (stopped_) return false;
      if (items_.size() >= capacity_) {
        items_.pop_front();
        ++dropped_;
      }
      items_.push_back(std::move(value));
      ++pushed_;
    }
    ready_.notify_one();
    return true;
  }

  // Appends `value`, waiting while the queue is full (lossless hand-over for sources that can
  // wait, e.g. recordings). Returns false when stopped (the value is discarded). Any thread.
  bool PushWait(T value) RIGCAL_EXCLUDES(mutex_) {
    {
      MutexLock lock(mutex_);
      while (!stopped_ && items_.size() >= capacity_) lock.Wait(space_);
      if (stopped_) return false;
      items_.push_back(std::move(value));
      ++pushed_;
    }
    ready_.notify_one();
    return true;
  }

  enum class WaitedPush { kPushed, kStopped, kTimedOut };
  // As PushWait, but gives up once `deadline` has passed: then `value` is left with the caller
  // (kTimedOut), so a producer that must also watch for a stop request can try again. Any thread.
  template <typename Clock, typename Duration>
  WaitedPush PushWaitUntil(T& value, const std::chrono::time_point<Clock, Duration>& deadline)
      RIGCAL_EXCLUDES(mutex_) {
    {
      MutexLock lock(mutex_);
      while (!stopped_ && items_.size() >= capacity_) {
        if (lock.WaitUntil(space_, deadline) == std::cv_status::timeout && !stopped_ &&
            items_.size() >= capacity_) {
          return WaitedPush::kTimedOut;
        }
      }
      if (stopped_) return WaitedPush::kStopped;
      items_.push_back(std::move(value));
      ++pushed_;
    }
    ready_.notify_one();
    return WaitedPush::kPushed;
  }

  // Next element; blocks until one is available. nullopt once stopped and drained. Any thread.
  std::optional<T> Pop() RIGCAL_EXCLUDES(mutex_) {
    MutexLock lock(mutex_);
    while (!stopped_ && items_.empty()) lock.Wait(ready_);
    return TakeFront();
  }

  // No more pushes; Pop drains what is left and then returns nullopt. Idempotent. Any thread.
  void Stop() RIGCAL_EXCLUDES(mutex_) {
    {
      MutexLock lock(mutex_);
      stopped_ = true;
    }
    ready_.notify_all();
    space_.notify_all();
  }

  size_t size() const RIGCAL_EXCLUDES(mutex_) {
    MutexLock lock(mutex_);
    return items_.size();
  }
  uint64_t dropped() const RIGCAL_EXCLUDES(mutex_) {
    MutexLock lock(mutex_);
    return dropped_;
  }
  uint64_t pushed() const RIGCAL_EXCLUDES(mutex_) {
    MutexLock lock(mutex_);
    return pushed_;
  }
  size_t capacity() const { return capacity_; }

 private:
  // The oldest element (removed; room for a waiting PushWait), or nullopt when empty.
  std::optional<T> TakeFront() RIGCAL_REQUIRES(mutex_) {
    if (items_.empty()) return std::nullopt;
    T value = std::move(items_.front());
    items_.pop_front();
    space_.notify_one();
    return value;
  }

  const size_t capacity_;
  mutable Mutex mutex_;
  std::condition_variable ready_;  // an element arrived, or Stop
  std::condition_variable space_;  // an element left, or Stop
  std::deque<T> items_ RIGCAL_GUARDED_BY(mutex_);
  bool stopped_ RIGCAL_GUARDED_BY(mutex_) = false;
  uint64_t dropped_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t pushed_ RIGCAL_GUARDED_BY(mutex_) = 0;
};

}  // namespace rigcal
