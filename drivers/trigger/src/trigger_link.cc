// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/trigger_link.h"

#include <cmath>
#include <optional>
#include <set>
#include <sstream>

#include "rigcal/base/logging.h"

namespace rigcal::trigger {

using trigger_proto::Message;
using trigger_proto::MessageType;

std::string TriggerMessageName(uint8_t type) {
  switch (static_cast<MessageType>(type)) {
    case MessageType::kHello:
      return "Hello";
    case MessageType::kPulseReport:
      return "PulseReport";
    case MessageType::kHeartbeat:
      return "Heartbeat";
    case MessageType::kAck:
      return "Ack";
    case MessageType::kNack:
      return "Nack";
    case MessageType::kExposureReport:
      return "ExposureReport";
    case MessageType::kSetRate:
      return "SetRate";
    case MessageType::kSetLine:
      return "SetLine";
    case MessageType::kStart:
      return "Start";
    case MessageType::kStop:
      return "Stop";
    case MessageType::kSetHeartbeat:
      return "SetHeartbeat";
    case MessageType::kGetInfo:
      return "GetInfo";
  }
  std::ostringstream s;
  s << "type 0x" << std::hex << static_cast<int>(type);
  return s.str();
}

uint32_t TriggerSettings::RateMilliHz() const {
  return static_cast<uint32_t>(std::llround(rate_hz * 1000.0));
}

Status TriggerSettings::Check() const {
  if (!(rate_hz * 1000.0 >= trigger_proto::kMinRateMilliHz &&
        rate_hz * 1000.0 <= trigger_proto::kMaxRateMilliHz)) {
    return Error{"rate_hz: must be in [0.1, 400], is " + std::to_string(rate_hz)};
  }
  if (lines.empty()) return Error{"lines: at least one trigger line"};
  const int64_t period = trigger_proto::PeriodUs(RateMilliHz());
  std::set<int> seen;
  for (size_t i = 0; i < lines.size(); ++i) {
    const TriggerLineSettings& l = lines[i];
    const std::string at = "lines[" + std::to_string(i) + "].";
    if (static_cast<uint8_t>(l.exposure_input) >
        static_cast<uint8_t>(trigger_proto::ExposureInput::kActiveLow)) {
      return Error{at + "exposure_input: must be none, active_high or active_low"};
    }
    if (l.line < 0 || l.line >= trigger_proto::kMaxLines) {
      return Error{at + "line: must be in [0, 8), is " + std::to_string(l.line)};
    }
    if (!seen.insert(l.line).second)
      return Error{at + "line: line " + std::to_string(l.line) + " twice"};
    const int64_t min_width = trigger_proto::kMinWidthUs;
    if (l.width_us < min_width || l.width_us > period - min_width) {
      return Error{at + "width_us: must be in [" + std::to_string(min_width) + ", period " +
                   std::to_string(period) + " us - " + std::to_string(min_width) + "], is " +
                   std::to_string(l.width_us)};
    }
    if (l.exposure_us < 0 || l.exposure_us > trigger_proto::kMaxExposureUs) {
      return Error{at + "exposure_us: must be in [0, 1000000], is " +
                   std::to_string(l.exposure_us)};
    }
    if (std::abs(l.phase_offset_us) + l.exposure_us / 2 >= period) {
      return Error{at + "phase_offset_us: |offset| + exposure / 2 must be below the period " +
                   std::to_string(period) + " us"};
    }
  }
  if (heartbeat_ms != 0 && (heartbeat_ms < trigger_proto::kMinHeartbeatMs ||
                            heartbeat_ms > trigger_proto::kMaxHeartbeatMs)) {
    return Error{"heartbeat_ms: must be 0 or in [10, 10000], is " + std::to_string(heartbeat_ms)};
  }
  int wired = 0;
  for (const TriggerLineSettings& l : lines) {
    wired += l.exposure_input != trigger_proto::ExposureInput::kNone ? 1 : 0;
  }
  const auto heartbeat = static_cast<uint16_t>(heartbeat_ms);
  if (!trigger_proto::FitsLink(RateMilliHz(), wired, heartbeat)) {
    return Error{
        "rate_hz: " + std::to_string(rate_hz) + " Hz with " + std::to_string(wired) +
        " exposure input(s) sends " +
        std::to_string(trigger_proto::LinkMilliBytesPerSecond(RateMilliHz(), wired, heartbeat) /
                       1000) +
        " B/s, above 90 % of the link's " + std::to_string(trigger_proto::kLinkBytesPerSecond) +
        " B/s"};
  }
  return Status::Ok();
}

TriggerLink::TriggerLink(std::unique_ptr<ByteStream> stream) : stream_(std::move(stream)) {}

Status TriggerLink::Poll(int timeout_ms, std::vector<TriggerEvent>* events) {
  uint8_t buffer[512];
  Expected<size_t> n = stream_->Read(buffer, sizeof(buffer), timeout_ms);
  if (!n) return Error{n.error()};
  const int64_t rx_ns = stream_->NowNs();
  for (size_t i = 0; i < *n; ++i) {
    ++frame_bytes_;
    const trigger_proto::DecodeEvent e = decoder_.Push(buffer[i]);
    if (e == trigger_proto::DecodeEvent::kMessage) {
      // The frame's bytes and those read after it crossed the wire after the MCU stamped it.
      const double wire_ns = uart_byte_ns_ * static_cast<double>(frame_bytes_ + (*n - 1 - i));
      events->push_back({decoder_.message(), rx_ns - std::llround(wire_ns)});
    } else if (e != trigger_proto::DecodeEvent::kNone) {
      if (e == trigger_proto::DecodeEvent::kUnsupportedVersion) {
        other_version_ = decoder_.raw_version();
      }
      ModuleLogger("trigger")->debug("trigger link: dropped a frame ({})", static_cast<int>(e));
    }
    if (buffer[i] == 0) frame_bytes_ = 0;  // the frame delimiter
  }
  return Status::Ok();
}

Status TriggerLink::Command(Message command, int timeout_ms, std::vector<TriggerEvent>* events) {
  const uint16_t id = next_command_id_++;
  switch (command.type) {
    case MessageType::kSetRate:
      command.set_rate.command_id = id;
      break;
    case MessageType::kSetLine:
      command.set_line.command_id = id;
      break;
    case MessageType::kSetHeartbeat:
      command.set_heartbeat.command_id = id;
      break;
    default:
      command.simple.command_id = id;
      break;
  }
  const std::string name = TriggerMessageName(static_cast<uint8_t>(command.type));
  uint8_t frame[trigger_proto::kMaxFrameSize];
  const size_t size = trigger_proto::EncodeFrame(command, frame, sizeof(frame));
  if (size == 0) return Error{"trigger link: cannot encode " + name};
  if (Status s = stream_->Write(frame, size); !s.ok()) return s;
  const int64_t deadline = stream_->NowNs() + int64_t{timeout_ms} * 1'000'000;
  while (stream_->NowNs() < deadline) {
    std::vector<TriggerEvent> got;
    if (Status s = Poll(20, &got); !s.ok()) return s;
    // The answer ends the wait; messages after it in the same read are kept too.
    std::optional<Status> answer;
    for (const TriggerEvent& e : got) {
      const Message& m = e.message;
      if (!answer && m.type == MessageType::kAck && m.ack.command_id == id) {
        answer = Status::Ok();
      } else if (!answer && m.type == MessageType::kNack && m.nack.command_id == id) {
        answer = Error{"trigger generator refused " + name + ": " +
                       trigger_proto::NackReasonName(m.nack.reason) +
                       (m.nack.field != trigger_proto::Field::kNone
                            ? std::string(" (") + trigger_proto::FieldName(m.nack.field) + ")"
                            : std::string())};
      } else {
        events->push_back(e);
      }
    }
    if (answer) return *answer;
  }
  return Error{"trigger link: no answer to " + name + " within " + std::to_string(timeout_ms) +
               " ms"};
}

Status TriggerLink::Apply(const TriggerSettings& settings, int timeout_ms,
                          std::vector<TriggerEvent>* events) {
  if (Status s = settings.Check(); !s.ok()) return s.Prefixed("trigger settings");
  Message m;
  m.type = MessageType::kStop;
  if (Status s = Command(m, timeout_ms, events); !s.ok()) return s;
  m = Message{};
  m.type = MessageType::kSetHeartbeat;
  m.set_heartbeat.period_ms = static_cast<uint16_t>(settings.heartbeat_ms);
  if (Status s = Command(m, timeout_ms, events); !s.ok()) return s;
  // Lines first at a slow rate would be refused if wider than the old period: disable all, set
  // the rate, then the lines.
  for (int line = 0; line < trigger_proto::kMaxLines; ++line) {
    m = Message{};
    m.type = MessageType::kSetLine;
    m.set_line.line = static_cast<uint8_t>(line);
    m.set_line.enabled = 0;
    m.set_line.width_us = trigger_proto::kMinWidthUs;
    if (Status s = Command(m, timeout_ms, events); !s.ok()) return s;
  }
  m = Message{};
  m.type = MessageType::kSetRate;
  m.set_rate.rate_mhz = settings.RateMilliHz();
  if (Status s = Command(m, timeout_ms, events); !s.ok()) return s;
  for (const TriggerLineSettings& l : settings.lines) {
    m = Message{};
    m.type = MessageType::kSetLine;
    m.set_line.line = static_cast<uint8_t>(l.line);
    m.set_line.enabled = 1;
    m.set_line.width_us = static_cast<uint32_t>(l.width_us);
    m.set_line.phase_offset_us = static_cast<int32_t>(l.phase_offset_us);
    m.set_line.exposure_us = static_cast<uint32_t>(l.exposure_us);
    m.set_line.exposure_input = l.exposure_input;
    if (Status s = Command(m, timeout_ms, events); !s.ok()) return s;
  }
  m = Message{};
  m.type = MessageType::kStart;
  return Command(m, timeout_ms, events);
}

Status TriggerLink::Stop(int timeout_ms, std::vector<TriggerEvent>* events) {
  Message m;
  m.type = MessageType::kStop;
  return Command(m, timeout_ms, events);
}

}  // namespace rigcal::trigger
