// SPDX-License-Identifier: Apache-2.0
#pragma once
// NotifySocket: the test's stand-in for systemd's notification socket (sd_notify(3)): a Unix
// datagram socket bound at a path (NOTIFY_SOCKET of the child), every message kept with the
// time it arrived. A thread of its own receives them; the destructor joins it.

#include <atomic>
#include <chrono>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace rigcal::device_test {

class NotifySocket {
 public:
  using Clock = std::chrono::steady_clock;
  struct Message {
    Clock::time_point at;
    std::string text;  // e.g. "READY=1\nSTATUS=...", "WATCHDOG=1", "STOPPING=1"
  };

  // Binds `path` (removed first); error() says why when it cannot.
  explicit NotifySocket(std::string path);
  ~NotifySocket();
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  const std::string& error() const { return error_; }
  const std::string& path() const { return path_; }
  std::vector<Message> Messages() const;
  // Arrival times of the messages one of whose lines is `line` ("WATCHDOG=1").
  std::vector<Clock::time_point> Times(const std::string& line) const;

 private:
  void Receive();

  std::string path_;
  std::string error_;
  int fd_ = -1;
  std::atomic<bool> stop_{false};
  mutable std::mutex mutex_;
  std::vector<Message> messages_;  // guarded by mutex_
  std::thread thread_;
};

}  // namespace rigcal::device_test
