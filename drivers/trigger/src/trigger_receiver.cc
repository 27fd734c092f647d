// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/trigger_receiver.h"

#include "rigcal/base/logging.h"

namespace rigcal::trigger {

TriggerSession::TriggerSession(std::unique_ptr<ByteStream> stream, TriggerSettings settings,
                               TriggerMatcher* matcher, int command_timeout_ms)
    : link_(std::move(stream)),
      settings_(std::move(settings)),
      matcher_(matcher),
      timeout_ms_(command_timeout_ms) {}

Status TriggerSession::Deliver(std::vector<TriggerEvent>* events) {
  bool rebooted = false;
  for (const TriggerEvent& e : *events) {
    matcher_->OnMessage(e.message, e.rx_ns);
    if (observer_) observer_(e);
    rebooted = rebooted || e.message.type == trigger_proto::MessageType::kHello;
  }
  events->clear();
  if (rebooted && started_) {
    ModuleLogger("trigger")->warn("trigger: the generator rebooted; applying the settings again");
    ++reconfigurations_;
    std::vector<TriggerEvent> more;
    const Status s = link_.Apply(settings_, timeout_ms_, &more);
    for (const TriggerEvent& e : more) {
      matcher_->OnMessage(e.message, e.rx_ns);
      if (observer_) observer_(e);
    }
    return s.Prefixed("trigger: re-applying the settings after a reboot");
  }
  return Status::Ok();
}

Status TriggerSession::Start() {
  std::vector<TriggerEvent> events;
  const Status s = link_.Apply(settings_, timeout_ms_, &events);
  (void)Deliver(&events);  // the boot Hello, if any, is before the start: no re-apply
  if (!s.ok()) return s;
  started_ = true;
  return Status::Ok();
}

Status TriggerSession::Pump(int timeout_ms) {
  std::vector<TriggerEvent> events;
  const Status s = link_.Poll(timeout_ms, &events);
  if (Status d = Deliver(&events); !d.ok()) return d;
  return s;
}

Status TriggerSession::Stop() {
  if (!started_) return Status::Ok();
  started_ = false;
  std::vector<TriggerEvent> events;
  const Status s = link_.Stop(timeout_ms_, &events);
  (void)Deliver(&events);  // re-applies nothing: stopped
  return s;
}

TriggerReceiver::TriggerReceiver(std::unique_ptr<TriggerSession> session)
    : session_(std::move(session)) {}

TriggerReceiver::~TriggerReceiver() { Stop(); }

Status TriggerReceiver::Start() {
  if (thread_.joinable()) return Status::Ok();
  if (Status s = session_->Start(); !s.ok()) return s;
  thread_ = std::thread([this] { Loop(); });
  return Status::Ok();
}

void TriggerReceiver::Loop() {
  while (!stop_.load()) {
    if (Status s = session_->Pump(20); !s.ok()) {
      ModuleLogger("trigger")->error("trigger: {}", s.message());
      MutexLock lock(mutex_);
      problem_ = s.message();
      return;
    }
  }
}

void TriggerReceiver::Stop() {
  stop_.store(true);
  if (thread_.joinable()) {
    thread_.join();
    (void)session_->Stop();
  }
}

std::string TriggerReceiver::problem() const {
  MutexLock lock(mutex_);
  return problem_;
}

}  // namespace rigcal::trigger
