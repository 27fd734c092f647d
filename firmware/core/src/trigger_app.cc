// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger_core/trigger_app.h"

namespace rigcal::trigger_core {
namespace {

uint16_t Saturate16(uint32_t v) { return v > 0xFFFFu ? 0xFFFFu : static_cast<uint16_t>(v); }

proto::NackReason ReasonOf(proto::DecodeEvent event) {
  switch (event) {
    case proto::DecodeEvent::kUnsupportedVersion:
      return proto::NackReason::kUnsupportedVersion;
    case proto::DecodeEvent::kUnknownType:
      return proto::NackReason::kUnknownType;
    case proto::DecodeEvent::kBadLength:
      return proto::NackReason::kBadLength;
    default:
      return proto::NackReason::kNone;
  }
}

}  // namespace

void TriggerApp::Boot(uint64_t now_us, BoardInfo board) {
  board_ = board;
  for (int line = 0; line < proto::kMaxLines; ++line) timers_->Release(line);
  SendHello(now_us);
  next_heartbeat_us_ = now_us;
}

void TriggerApp::OnRxByte(uint8_t byte, uint64_t now_us) {
  const proto::DecodeEvent event = decoder_.Push(byte);
  if (event == proto::DecodeEvent::kMessage) {
    HandleCommand(decoder_.message(), now_us);
    return;
  }
  const proto::NackReason reason = ReasonOf(event);
  if (reason != proto::NackReason::kNone) {
    Answer(decoder_.command_id(), decoder_.raw_type(), {reason, proto::Field::kNone});
  }
}

void TriggerApp::HandleCommand(const proto::Message& m, uint64_t now_us) {
  const uint8_t type = static_cast<uint8_t>(m.type);
  if (!proto::IsCommand(type)) {  // an MCU -> host message sent to the MCU
    Answer(0, type, {proto::NackReason::kUnknownType, proto::Field::kNone});
    return;
  }
  const ConfigProblem busy{proto::NackReason::kBusy, proto::Field::kNone};
  switch (m.type) {
    case proto::MessageType::kSetRate: {
      if (scheduler_.running()) return Answer(m.set_rate.command_id, type, busy);
      TriggerConfig next = config_;
      next.rate_mhz = m.set_rate.rate_mhz;
      ConfigProblem problem = CheckRate(next.rate_mhz);
      // A rate whose period is too short for a configured line, or whose reports do not fit the
      // link, is refused as a rate problem.
      if (problem.ok() && !CheckConfig(next).ok())
        problem = {proto::NackReason::kOutOfRange, proto::Field::kRate};
      if (problem.ok()) {
        config_ = next;
        scheduler_.Configure(config_);
      }
      return Answer(m.set_rate.command_id, type, problem);
    }
    case proto::MessageType::kSetLine: {
      const proto::SetLine& s = m.set_line;
      if (scheduler_.running()) return Answer(s.command_id, type, busy);
      if (s.line >= proto::kMaxLines || s.enabled > 1) {
        return Answer(s.command_id, type, {proto::NackReason::kOutOfRange, proto::Field::kLine});
      }
      LineConfig line;
      line.enabled = s.enabled == 1;
      line.width_us = s.width_us;
      line.phase_offset_us = s.phase_offset_us;
      line.exposure_us = s.exposure_us;
      line.exposure_input = s.exposure_input;
      ConfigProblem problem = CheckLine(line, config_.rate_mhz);
      TriggerConfig next = config_;
      next.lines[s.line] = line;
      if (problem.ok() && !next.FitsLink()) {
        problem = {proto::NackReason::kOutOfRange, proto::Field::kExposureInput};
      }
      if (problem.ok()) {
        config_.lines[s.line] = line;
        scheduler_.Configure(config_);
      }
      return Answer(s.command_id, type, problem);
    }
    case proto::MessageType::kSetHeartbeat: {
      ConfigProblem problem = CheckHeartbeat(m.set_heartbeat.period_ms);
      TriggerConfig next = config_;
      next.heartbeat_period_ms = m.set_heartbeat.period_ms;
      if (problem.ok() && !next.FitsLink()) {
        problem = {proto::NackReason::kOutOfRange, proto::Field::kHeartbeatPeriod};
      }
      if (problem.ok()) {
        config_.heartbeat_period_ms = m.set_heartbeat.period_ms;
        next_heartbeat_us_ = now_us + 1000ull * config_.heartbeat_period_ms;
      }
      return Answer(m.set_heartbeat.command_id, type, problem);
    }
    case proto::MessageType::kStart: {
      if (!scheduler_.running() && config_.EnabledMask() == 0) {
        return Answer(m.simple.command_id, type,
                      {proto::NackReason::kNoLinesEnabled, proto::Field::kLine});
      }
      if (!scheduler_.running()) StartRun(now_us);
      return Answer(m.simple.command_id, type, {});
    }
    case proto::MessageType::kStop:
      scheduler_.Stop(timers_);
      return Answer(m.simple.command_id, type, {});
    case proto::MessageType::kGetInfo:
      Answer(m.simple.command_id, type, {});
      SendHello(now_us);
      return;
    default:
      return Answer(0, type, {proto::NackReason::kUnknownType, proto::Field::kNone});
  }
}

void TriggerApp::StartRun(uint64_t now_us) {
  meter_.Start();
  scheduler_.Start(now_us, timers_);
  for (int line = 0; line < proto::kMaxLines; ++line) {
    if (config_.lines[line].wired())
      timers_->StartCapture(line, config_.lines[line].exposure_input);
  }
}

void TriggerApp::Answer(uint16_t id, uint8_t type, ConfigProblem problem) {
  proto::Message m;
  if (problem.ok()) {
    m.type = proto::MessageType::kAck;
    m.ack.command_id = id;
    m.ack.command = static_cast<proto::MessageType>(type);
  } else {
    m.type = proto::MessageType::kNack;
    m.nack.command_id = id;
    m.nack.command = type;
    m.nack.reason = problem.reason;
    m.nack.field = problem.field;
  }
  Send(m);
}

void TriggerApp::Poll(uint64_t now_us) {
  proto::Message m;
  m.type = proto::MessageType::kPulseReport;
  while (scheduler_.PopReport(now_us, &m.pulse)) Send(m);
  m.type = proto::MessageType::kExposureReport;
  while (meter_.Pop(&m.exposure)) Send(m);
  if (config_.heartbeat_period_ms != 0 && now_us >= next_heartbeat_us_) {
    SendHeartbeat(now_us);
    const uint64_t period = 1000ull * config_.heartbeat_period_ms;
    next_heartbeat_us_ += period;
    if (next_heartbeat_us_ <= now_us) next_heartbeat_us_ = now_us + period;  // fell behind
  }
}

void TriggerApp::SendHeartbeat(uint64_t now_us) {
  proto::Message m;
  m.type = proto::MessageType::kHeartbeat;
  m.heartbeat.mcu_time_us = now_us;
  m.heartbeat.next_seq = scheduler_.next_seq();
  m.heartbeat.running = scheduler_.running() ? 1 : 0;
  m.heartbeat.late_edges = Saturate16(scheduler_.late_edges());
  m.heartbeat.rx_errors = Saturate16(rx_errors());
  m.heartbeat.tx_dropped = Saturate16(tx_dropped());
  m.heartbeat.skipped_ticks = Saturate16(scheduler_.skipped_ticks());
  Send(m);
}

void TriggerApp::SendHello(uint64_t now_us) {
  proto::Message m;
  m.type = proto::MessageType::kHello;
  m.hello.firmware_version = kFirmwareVersion;
  m.hello.max_lines = proto::kMaxLines;
  m.hello.mcu_time_us = now_us;
  m.hello.clock_status = board_.clock_status;
  m.hello.hse_mhz = board_.hse_mhz;
  Send(m);
}

void TriggerApp::Send(const proto::Message& m) {
  uint8_t frame[proto::kMaxFrameSize];
  const size_t size = proto::EncodeFrame(m, frame, sizeof(frame));
  if (size == 0 || size > kTxCapacity - tx_size_) {
    ++tx_dropped_;
    return;
  }
  for (size_t i = 0; i < size; ++i) tx_[(tx_head_ + tx_size_ + i) % kTxCapacity] = frame[i];
  tx_size_ += size;
}

bool TriggerApp::PopTx(uint8_t* byte) {
  if (tx_size_ == 0) return false;
  *byte = tx_[tx_head_];
  tx_head_ = (tx_head_ + 1) % kTxCapacity;
  --tx_size_;
  return true;
}

}  // namespace rigcal::trigger_core
