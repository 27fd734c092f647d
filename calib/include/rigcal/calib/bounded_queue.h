#pragma once
// BoundedQueue: a fixed-capacity multi-producer queue between pipeline threads. Push never
// blocks: when full, the oldest element is dropped and counted (capture must never wait for
// a slow consumer); PushWait waits for room instead (sources that can wait). Pop blocks until
// an element arrives or the queue is stopped. Every member is thread-safe.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>

namespace rigcal {

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  // Appends `value`; drops the oldest element when full. Returns false when stopped (the
  // value is discarded). Any thread.
  bool Push(T value) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
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
  // wait, e.g. recordings). Returns false when stopped (the value is discarded).
  bool PushWait(T value) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      space_.wait(lock, [&] { return stopped_ || items_.size() < capacity_; });
      if (stopped_) return false;
      items_.push_back(std::move(value));
      ++pushed_;
    }
    ready_.notify_one();
    return true;
  }

  // Next element; blocks until one is available. nullopt once stopped and drained.
  std::optional<T> Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [&] { return stopped_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T value = std::move(items_.front());
    items_.pop_front();
    space_.notify_one();
    return value;
  }

  // Like Pop, but gives up after `timeout` (nullopt).
  template <typename Duration>
  std::optional<T> PopFor(Duration timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait_for(lock, timeout, [&] { return stopped_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T value = std::move(items_.front());
    items_.pop_front();
    space_.notify_one();
    return value;
  }

  // No more pushes; Pop drains what is left and then returns nullopt. Idempotent.
  void Stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopped_ = true;
    }
    ready_.notify_all();
    space_.notify_all();
  }

  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  uint64_t pushed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return pushed_;
  }
  size_t capacity() const { return capacity_; }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::condition_variable space_;
  std::deque<T> items_;
  bool stopped_ = false;
  uint64_t dropped_ = 0;
  uint64_t pushed_ = 0;
};

}  // namespace rigcal
