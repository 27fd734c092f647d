// SPDX-License-Identifier: Apache-2.0
#pragma once
// TriggerSession: a configured trigger generator feeding a TriggerMatcher. It applies the
// settings, then pumps the link: every message goes to the matcher; a Hello after the start
// (the MCU rebooted and lost its configuration) makes it apply the settings again.
// TriggerReceiver: one thread that pumps a session until Stop() (live links).
//
// Threads: a TriggerSession belongs to one thread. TriggerReceiver: the owner calls Start/Stop;
// the matcher is read by any thread (capture sources).

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/trigger/trigger_link.h"
#include "rigcal/trigger/trigger_matcher.h"

namespace rigcal::trigger {

class TriggerSession {
 public:
  // `matcher` is not owned and must outlive the session.
  TriggerSession(std::unique_ptr<ByteStream> stream, TriggerSettings settings,
                 TriggerMatcher* matcher, int command_timeout_ms = 1000);

  // Applies the settings and starts the trigger. Errors: invalid settings (by field), a refused
  // command (reason and field), no answer.
  Status Start();
  // Reads for up to `timeout_ms` and hands every message to the matcher; re-applies the
  // settings after an MCU reboot. Error: the stream failed, or re-applying failed.
  Status Pump(int timeout_ms);
  Status Stop();

  // Called with every message after the matcher has seen it (recording, tests). Same thread.
  void set_observer(std::function<void(const TriggerEvent&)> observer) {
    observer_ = std::move(observer);
  }
  int reconfigurations() const { return reconfigurations_; }
  TriggerLink& link() { return link_; }

 private:
  Status Deliver(std::vector<TriggerEvent>* events);

  TriggerLink link_;
  TriggerSettings settings_;
  TriggerMatcher* matcher_;
  int timeout_ms_;
  std::function<void(const TriggerEvent&)> observer_;
  bool started_ = false;
  int reconfigurations_ = 0;
};

class TriggerReceiver {
 public:
  explicit TriggerReceiver(std::unique_ptr<TriggerSession> session);
  ~TriggerReceiver();
  TriggerReceiver(const TriggerReceiver&) = delete;
  TriggerReceiver& operator=(const TriggerReceiver&) = delete;

  // Starts the trigger (TriggerSession::Start, on the calling thread), then the pump thread.
  Status Start();
  // Ends the pump thread and stops the trigger. Idempotent.
  void Stop();
  // The pump's failure ("" while it runs fine). Any thread.
  std::string problem() const RIGCAL_EXCLUDES(mutex_);

 private:
  void Loop();
  std::unique_ptr<TriggerSession> session_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  mutable Mutex mutex_;
  std::string problem_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::trigger
