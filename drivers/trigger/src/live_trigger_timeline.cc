// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/live_trigger_timeline.h"

#include <chrono>
#include <cmath>
#include <thread>

#include "rigcal/base/logging.h"
#include "rigcal/trigger/serial_port.h"

namespace rigcal::trigger {

const char* ToString(FrameStamp stamp) {
  switch (stamp) {
    case FrameStamp::kStartOfExposure:
      return "start_of_exposure";
    case FrameStamp::kExposureCentre:
      return "exposure_centre";
    case FrameStamp::kEndOfFrame:
      return "end_of_frame";
  }
  return "?";
}

std::optional<FrameStamp> FrameStampFromString(const std::string& text) {
  for (FrameStamp s :
       {FrameStamp::kStartOfExposure, FrameStamp::kExposureCentre, FrameStamp::kEndOfFrame}) {
    if (text == ToString(s)) return s;
  }
  return std::nullopt;
}

int64_t StampOffsetNs(FrameStamp stamp, int64_t exposure_us, int64_t readout_us) {
  switch (stamp) {
    case FrameStamp::kStartOfExposure:
      return -exposure_us * 1000 / 2;
    case FrameStamp::kExposureCentre:
      return 0;
    case FrameStamp::kEndOfFrame:
      return exposure_us * 1000 / 2 + readout_us * 1000;
  }
  return 0;
}

Status LiveTriggerOptions::Check() const {
  if (port.empty()) return Error{"port: missing"};
  if (baud <= 0) return Error{"baud: must be > 0"};
  if (command_timeout_ms < 10 || command_timeout_ms > 60000) {
    return Error{"command_timeout_ms: must be in [10, 60000]"};
  }
  if (listen_ms < 0 || listen_ms > 60000) return Error{"listen_ms: must be in [0, 60000]"};
  if (Status s = settings.Check(); !s.ok()) return s;
  return matcher.Check().Prefixed("matcher");
}

Expected<std::unique_ptr<LiveTriggerTimeline>> LiveTriggerTimeline::Start(
    const LiveTriggerOptions& options) {
  const std::string at = "trigger generator on " + options.port + ": ";
  if (Status s = options.Check(); !s.ok()) return Error{at + s.message()};
  auto port = SerialPort::Open(options.port, options.baud);
  if (!port) return Error{"trigger generator: " + port.error()};
  std::unique_ptr<LiveTriggerTimeline> t(new LiveTriggerTimeline(options));
  auto session = std::make_unique<TriggerSession>(std::move(*port), options.settings, &t->matcher_,
                                                  options.command_timeout_ms);
  if (options.uart_wire) session->link().set_uart_byte_ns(1e10 / options.baud);
  // Bytes sent while the generator boots are lost: wait until it speaks (or give up waiting).
  std::vector<TriggerEvent> heard;
  const auto listen_end =
      std::chrono::steady_clock::now() + std::chrono::milliseconds(options.listen_ms);
  while (heard.empty() && std::chrono::steady_clock::now() < listen_end) {
    if (Status s = session->link().Poll(50, &heard); !s.ok()) return Error{at + s.message()};
  }
  if (heard.empty() && options.listen_ms > 0) {
    ModuleLogger("trigger")->info("{}silent for {} ms; configuring it anyway", at,
                                  options.listen_ms);
  }
  LiveTriggerTimeline* self = t.get();
  session->set_observer([self](const TriggerEvent& e) {
    if (e.message.type != trigger_protocol::MessageType::kPulseReport) return;
    MutexLock lock(self->mutex_);
    self->last_ = {true, e.message.pulse.seq, e.message.pulse.mcu_time_us};
  });
  t->receiver_ = std::make_unique<TriggerReceiver>(std::move(session));
  if (Status s = t->receiver_->Start(); !s.ok()) return Error{at + s.message()};
  ModuleLogger("trigger")->info("{}running at {} Hz on {} line(s)", at, options.settings.rate_hz,
                                options.settings.lines.size());
  return t;
}

LiveTriggerTimeline::~LiveTriggerTimeline() { Stop(); }

void LiveTriggerTimeline::Stop() {
  if (receiver_) receiver_->Stop();
}

std::string LiveTriggerTimeline::problem() const {
  const std::string p = receiver_ ? receiver_->problem() : std::string();
  return p.empty() ? p : options_.port + ": " + p;
}

Expected<LiveTriggerTimeline::Tick> LiveTriggerTimeline::NextTick(int64_t not_before_ns,
                                                                  int64_t timeout_ns) const {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::nanoseconds(timeout_ns);
  const double period_us = 1e6 / options_.settings.rate_hz;
  while (true) {
    if (const std::string p = problem(); !p.empty()) return Error{"trigger generator on " + p};
    LastPulse last;
    {
      MutexLock lock(mutex_);
      last = last_;
    }
    if (last.seen && matcher_.stats().synced) {
      const std::optional<int64_t> last_ns = matcher_.MapMcuTime(last.mcu_us);
      if (last_ns) {
        // Ticks after the last reported one: T_k = T_last + k * period (to within 1 us).
        const int64_t k =
            not_before_ns <= *last_ns
                ? 0
                : static_cast<int64_t>(std::ceil(static_cast<double>(not_before_ns - *last_ns) /
                                                 (period_us * 1000.0)));
        const auto tick_us = last.mcu_us + static_cast<uint64_t>(std::llround(k * period_us));
        const std::optional<int64_t> tick_ns = matcher_.MapMcuTime(tick_us);
        if (tick_ns) return Tick{tick_us, *tick_ns};
      }
    }
    if (std::chrono::steady_clock::now() >= give_up) {
      return Error{"trigger generator on " + options_.port + ": no pulse reports within " +
                   std::to_string(timeout_ns / 1'000'000) + " ms (is the trigger running?)"};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace rigcal::trigger
