// SPDX-License-Identifier: Apache-2.0
// The firmware logic without the board (firmware/core TriggerApp): command answers (Ack, every
// Nack reason with its field, the link budget), heartbeats, the transmit queue, a run of pulse
// reports on ideal compare timers, and exposure reports from captured exposure edges, driven
// through the protocol's byte stream exactly as the UART would.
#include "rigcal/trigger_core/trigger_app.h"

#include <gtest/gtest.h>

#include <vector>

#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::trigger_core {
namespace {

using proto::Field;
using proto::Message;
using proto::MessageType;
using proto::NackReason;

class Lines : public EdgeSink {
 public:
  void OnEdge(const LineEdge& e) override {
    if (e.line == 0 && e.high) rises0.push_back(e.t_us);
  }
  std::vector<uint64_t> rises0;
};

// The board around a TriggerApp: sends commands as frames, drains and decodes its output; its
// timers are ideal (IdealLineTimers).
class Board {
 public:
  Board() : timers(&lines), app(&timers) {
    timers.set_now(now);
    app.Boot(now, {proto::kClockHseFallback, 25});
  }

  void SendBytes(const std::vector<uint8_t>& bytes) {
    for (uint8_t b : bytes) app.OnRxByte(b, now);
  }
  void Send(const Message& m) {
    std::vector<uint8_t> f(proto::kMaxFrameSize);
    f.resize(proto::EncodeFrame(m, f.data(), f.size()));
    SendBytes(f);
  }
  // Runs the main loop until `t_us` in steps of `step_us`, draining the UART each time.
  void RunTo(uint64_t t_us, uint64_t step_us = 10) {
    while (now < t_us) {
      now += step_us;
      timers.RunUntil(now, &app);
      app.Poll(now);
      Drain();
    }
  }
  void Drain() {
    uint8_t b;
    while (app.PopTx(&b)) {
      if (decoder.Push(b) == proto::DecodeEvent::kMessage) received.push_back(decoder.message());
    }
  }
  // Messages of one type received so far (and forgets them).
  std::vector<Message> Take(MessageType type) {
    Drain();
    std::vector<Message> out, rest;
    for (const Message& m : received) (m.type == type ? out : rest).push_back(m);
    received = rest;
    return out;
  }
  // Sends a command and returns its single answer (Ack or Nack).
  Message Ask(const Message& m) {
    Send(m);
    Drain();
    std::vector<Message> answers, rest;
    for (const Message& r : received) {
      (r.type == MessageType::kAck || r.type == MessageType::kNack ? answers : rest).push_back(r);
    }
    received = rest;
    EXPECT_EQ(answers.size(), 1u);
    return answers.empty() ? Message{} : answers[0];
  }

  Lines lines;
  IdealLineTimers timers;
  TriggerApp app;
  proto::MessageDecoder decoder;
  std::vector<Message> received;
  uint64_t now = 5'000;
};

Message SetRate(uint16_t id, uint32_t rate_mhz) {
  Message m;
  m.type = MessageType::kSetRate;
  m.set_rate = {id, rate_mhz};
  return m;
}
Message SetLine(uint16_t id, uint8_t line, uint8_t enabled, uint32_t width, int32_t offset = 0,
                uint32_t exposure = 0, proto::ExposureInput input = proto::ExposureInput::kNone) {
  Message m;
  m.type = MessageType::kSetLine;
  m.set_line = {id, line, enabled, width, offset, exposure, input};
  return m;
}
Message Simple(MessageType type, uint16_t id) {
  Message m;
  m.type = type;
  m.simple.command_id = id;
  return m;
}

void ExpectAck(const Message& a, uint16_t id, MessageType command) {
  ASSERT_EQ(a.type, MessageType::kAck) << "reason " << proto::NackReasonName(a.nack.reason);
  EXPECT_EQ(a.ack.command_id, id);
  EXPECT_EQ(a.ack.command, command);
}
void ExpectNack(const Message& a, uint16_t id, NackReason reason, Field field) {
  ASSERT_EQ(a.type, MessageType::kNack);
  EXPECT_EQ(a.nack.command_id, id);
  EXPECT_EQ(a.nack.reason, reason) << proto::NackReasonName(a.nack.reason);
  EXPECT_EQ(a.nack.field, field) << proto::FieldName(a.nack.field);
}

TEST(TriggerApp, BootSaysHelloAndDropsTheLines) {
  Board b;
  const std::vector<Message> hello = b.Take(MessageType::kHello);
  ASSERT_EQ(hello.size(), 1u);
  EXPECT_EQ(hello[0].hello.firmware_version, kFirmwareVersion);
  EXPECT_EQ(hello[0].hello.max_lines, proto::kMaxLines);
  EXPECT_EQ(hello[0].hello.mcu_time_us, 5'000u);
  EXPECT_EQ(hello[0].hello.clock_status, proto::kClockHseFallback);  // what the board said
  EXPECT_EQ(hello[0].hello.hse_mhz, 25);
  EXPECT_EQ(b.timers.levels(), 0);
  ExpectAck(b.Ask(Simple(MessageType::kGetInfo, 3)), 3, MessageType::kGetInfo);
  EXPECT_EQ(b.Take(MessageType::kHello).size(), 1u);
}

TEST(TriggerApp, RefusesOutOfRangeValuesWithTheField) {
  Board b;
  ExpectNack(b.Ask(SetRate(1, 99)), 1, NackReason::kOutOfRange, Field::kRate);
  ExpectNack(b.Ask(SetRate(2, 400'001)), 2, NackReason::kOutOfRange, Field::kRate);
  ExpectAck(b.Ask(SetRate(3, 400'000)), 3, MessageType::kSetRate);  // 2500 µs
  ExpectNack(b.Ask(SetLine(4, 8, 1, 100)), 4, NackReason::kOutOfRange, Field::kLine);
  ExpectNack(b.Ask(SetLine(5, 0, 2, 100)), 5, NackReason::kOutOfRange, Field::kLine);
  ExpectNack(b.Ask(SetLine(6, 0, 1, 24)), 6, NackReason::kOutOfRange, Field::kWidth);
  ExpectNack(b.Ask(SetLine(7, 0, 1, 2'476)), 7, NackReason::kOutOfRange, Field::kWidth);
  ExpectNack(b.Ask(SetLine(8, 0, 1, 100, 0, 1'000'001)), 8, NackReason::kOutOfRange,
             Field::kExposure);
  ExpectNack(b.Ask(SetLine(9, 0, 1, 100, -2'000, 1'000)), 9, NackReason::kOutOfRange,
             Field::kPhaseOffset);
  ExpectAck(b.Ask(SetLine(10, 0, 1, 2'475, -1'999, 1'000)), 10, MessageType::kSetLine);
  // At 400 Hz no exposure report fits the link beside the pulse reports.
  ExpectNack(b.Ask(SetLine(16, 1, 1, 100, 0, 0, proto::ExposureInput::kActiveHigh)), 16,
             NackReason::kOutOfRange, Field::kExposureInput);
  ExpectNack(b.Ask(SetLine(17, 1, 1, 100, 0, 0, static_cast<proto::ExposureInput>(3))), 17,
             NackReason::kOutOfRange, Field::kExposureInput);
  // A slower rate is fine; a faster one would make line 0's width exceed the period.
  ExpectNack(b.Ask(SetRate(11, 400'001)), 11, NackReason::kOutOfRange, Field::kRate);
  ExpectAck(b.Ask(SetRate(12, 20'000)), 12, MessageType::kSetRate);
  ExpectAck(b.Ask(SetLine(13, 0, 1, 2'475, 0, 1'000, proto::ExposureInput::kActiveLow)), 13,
            MessageType::kSetLine);
  // 400 Hz with a wired line exceeds the link: refused as a rate problem.
  ExpectNack(b.Ask(SetRate(18, 400'000)), 18, NackReason::kOutOfRange, Field::kRate);
  ExpectAck(b.Ask(SetLine(19, 0, 1, 2'475, 0, 1'000)), 19, MessageType::kSetLine);
  ExpectAck(b.Ask(SetRate(14, 400'000)), 14, MessageType::kSetRate);
  Message hb;
  hb.type = MessageType::kSetHeartbeat;
  hb.set_heartbeat = {15, 9};
  ExpectNack(b.Ask(hb), 15, NackReason::kOutOfRange, Field::kHeartbeatPeriod);
  // Refused values changed nothing.
  EXPECT_EQ(b.app.config().rate_mhz, 400'000u);
  EXPECT_EQ(b.app.config().lines[0].width_us, 2'475u);
  EXPECT_EQ(b.app.config().lines[1].enabled, false);
  EXPECT_EQ(b.app.config().heartbeat_period_ms, 100u);
}

TEST(TriggerApp, StartNeedsALineAndConfigWaitsForStop) {
  Board b;
  ExpectNack(b.Ask(Simple(MessageType::kStart, 1)), 1, NackReason::kNoLinesEnabled, Field::kLine);
  ExpectAck(b.Ask(SetLine(2, 2, 1, 100)), 2, MessageType::kSetLine);
  ExpectAck(b.Ask(Simple(MessageType::kStart, 3)), 3, MessageType::kStart);
  ExpectAck(b.Ask(Simple(MessageType::kStart, 4)), 4, MessageType::kStart);  // no-op
  ExpectNack(b.Ask(SetRate(5, 10'000)), 5, NackReason::kBusy, Field::kNone);
  ExpectNack(b.Ask(SetLine(6, 1, 1, 100)), 6, NackReason::kBusy, Field::kNone);
  ExpectAck(b.Ask(Simple(MessageType::kStop, 7)), 7, MessageType::kStop);
  ExpectAck(b.Ask(SetRate(8, 10'000)), 8, MessageType::kSetRate);
}

TEST(TriggerApp, AnswersBadFramesThatCarryACommandIdAndCountsTheRest) {
  Board b;
  b.Take(MessageType::kHello);
  // Wrong version with a valid CRC: Nack naming the command id.
  uint8_t payload[8] = {1, 0x10, 0x22, 0x11, 1, 0, 0, 0};  // protocol version 1
  const uint16_t crc = proto::Crc16(payload, 6);
  payload[6] = static_cast<uint8_t>(crc & 0xFF);
  payload[7] = static_cast<uint8_t>(crc >> 8);
  std::vector<uint8_t> frame(proto::CobsEncodedSize(8));
  frame.resize(proto::CobsEncode(payload, 8, frame.data(), frame.size()));
  frame.push_back(0);
  b.received.clear();
  b.SendBytes(frame);
  b.Drain();
  ASSERT_EQ(b.received.size(), 1u);
  ExpectNack(b.received[0], 0x1122, NackReason::kUnsupportedVersion, Field::kNone);
  b.received.clear();
  // A message of the MCU's own kind sent to it: unknown command.
  Message pulse;
  pulse.type = MessageType::kPulseReport;
  ExpectNack(b.Ask(pulse), 0, NackReason::kUnknownType, Field::kNone);
  // A corrupted frame (CRC) is not answered, only counted; the next command works.
  std::vector<uint8_t> f(proto::kMaxFrameSize);
  f.resize(proto::EncodeFrame(SetRate(9, 10'000), f.data(), f.size()));
  f[3] ^= 0x10;
  b.received.clear();
  b.SendBytes(f);
  b.Drain();
  EXPECT_TRUE(b.received.empty());
  EXPECT_EQ(b.app.config().rate_mhz, 20'000u);
  ExpectAck(b.Ask(SetRate(10, 10'000)), 10, MessageType::kSetRate);
  b.RunTo(b.now + 100'000);
  const std::vector<Message> hb = b.Take(MessageType::kHeartbeat);
  ASSERT_FALSE(hb.empty());
  EXPECT_EQ(hb.back().heartbeat.rx_errors, 2u);  // version, CRC (the pulse was a valid frame)
}

TEST(TriggerApp, HeartbeatsFollowTheirPeriodAndCanBeSwitchedOff) {
  Board b;
  b.RunTo(1'005'000, 100);
  std::vector<Message> hb = b.Take(MessageType::kHeartbeat);
  ASSERT_EQ(hb.size(), 11u);  // at the first poll after boot (5.1 ms), then every 100 ms
  EXPECT_EQ(hb[0].heartbeat.mcu_time_us, 5'100u);
  for (size_t i = 1; i < hb.size(); ++i) {
    EXPECT_EQ(hb[i].heartbeat.mcu_time_us, 5'000 + 100'000 * i);
    EXPECT_EQ(hb[i].heartbeat.running, 0);
  }
  Message off;
  off.type = MessageType::kSetHeartbeat;
  off.set_heartbeat = {1, 0};
  ExpectAck(b.Ask(off), 1, MessageType::kSetHeartbeat);
  b.RunTo(2'000'000, 100);
  EXPECT_TRUE(b.Take(MessageType::kHeartbeat).empty());
}

TEST(TriggerApp, ARunReportsEveryPulseInOrderAtItsRate) {
  Board b;
  ExpectAck(b.Ask(SetRate(1, 50'000)), 1, MessageType::kSetRate);  // 50 Hz
  ExpectAck(b.Ask(SetLine(2, 0, 1, 1'000, 0, 4'000)), 2, MessageType::kSetLine);
  ExpectAck(b.Ask(SetLine(3, 1, 1, 1'000, 0, 4'000)), 3, MessageType::kSetLine);
  ExpectAck(b.Ask(Simple(MessageType::kStart, 4)), 4, MessageType::kStart);
  const uint64_t start = b.now + Scheduler::kArmLeadUs;
  b.RunTo(start + 2'000'000 - 1'000, 10);
  const std::vector<Message> pulses = b.Take(MessageType::kPulseReport);
  ASSERT_EQ(pulses.size(), 100u);
  for (size_t k = 0; k < pulses.size(); ++k) {
    EXPECT_EQ(pulses[k].pulse.seq, k);
    EXPECT_EQ(pulses[k].pulse.line_mask, 0x03);
    EXPECT_EQ(pulses[k].pulse.mcu_time_us, start + 2'000 + 20'000 * k);  // lead: exposure / 2
  }
  ASSERT_EQ(b.lines.rises0.size(), 100u);
  EXPECT_EQ(b.lines.rises0[99], start + 20'000 * 99);  // rises 2 ms before T_k
  const std::vector<Message> hb = b.Take(MessageType::kHeartbeat);
  ASSERT_FALSE(hb.empty());
  EXPECT_EQ(hb.back().heartbeat.running, 1);
  EXPECT_EQ(hb.back().heartbeat.late_edges, 0);
  // next_seq: the reports sent before the heartbeat (each leaves at its T_k here).
  uint32_t before = 0;
  for (const Message& p : pulses) before += p.pulse.mcu_time_us <= hb.back().heartbeat.mcu_time_us;
  EXPECT_EQ(hb.back().heartbeat.next_seq, before);
  EXPECT_EQ(b.app.scheduler().next_seq(), 100u);
  EXPECT_EQ(hb.back().heartbeat.tx_dropped, 0);
}

TEST(TriggerApp, AFullTransmitQueueDropsWholeFrames) {
  Board b;
  ExpectAck(b.Ask(SetRate(1, 400'000)), 1, MessageType::kSetRate);
  ExpectAck(b.Ask(SetLine(2, 0, 1, 100)), 2, MessageType::kSetLine);
  ExpectAck(b.Ask(Simple(MessageType::kStart, 3)), 3, MessageType::kStart);
  // Nobody drains the UART for a second: 400 reports do not fit.
  for (uint64_t t = b.now; t < b.now + 1'000'000; t += 10) {
    b.timers.RunUntil(t, &b.app);
    b.app.Poll(t);
  }
  b.now += 1'000'000;
  EXPECT_GT(b.app.tx_dropped(), 0u);
  EXPECT_LE(b.app.tx_pending(), TriggerApp::kTxCapacity);
  b.Drain();
  EXPECT_EQ(b.decoder.stats().Errors(), 0u);  // only whole frames were queued
  const std::vector<Message> pulses = b.Take(MessageType::kPulseReport);
  ASSERT_GT(pulses.size(), 10u);
  for (size_t k = 1; k < pulses.size(); ++k) {
    EXPECT_EQ(pulses[k].pulse.seq, pulses[k - 1].pulse.seq + 1);  // the oldest ones are kept
  }
}

TEST(TriggerApp, WiredLinesReportTheirMeasuredExposures) {
  Board b;
  ExpectAck(b.Ask(SetRate(1, 50'000)), 1, MessageType::kSetRate);  // 50 Hz
  ExpectAck(b.Ask(SetLine(2, 0, 1, 100, 0, 4'000, proto::ExposureInput::kActiveHigh)), 2,
            MessageType::kSetLine);
  ExpectAck(b.Ask(SetLine(3, 1, 1, 100, 0, 4'000)), 3, MessageType::kSetLine);  // not wired
  ExpectAck(b.Ask(Simple(MessageType::kStart, 4)), 4, MessageType::kStart);
  EXPECT_EQ(b.timers.capture(0), proto::ExposureInput::kActiveHigh);
  EXPECT_EQ(b.timers.capture(1), proto::ExposureInput::kNone);
  // The camera on line 0 starts exposing 23 µs after each trigger rise, for 3000 + k µs (its
  // auto exposure shortened the configured 4 ms); the capture channel sees both edges.
  size_t seen = 0;
  for (int step = 0; step < 600; ++step) {
    b.RunTo(b.now + 1'000, 1'000);
    while (seen < b.lines.rises0.size()) {
      const uint64_t rise = b.lines.rises0[seen];
      const uint64_t start = rise + 23, end = start + 3'000 + seen;
      EXPECT_TRUE(b.app.meter().ExpectsStart(0));
      b.app.OnCapture(0, static_cast<uint32_t>(start));
      EXPECT_FALSE(b.app.meter().ExpectsStart(0));
      b.app.OnCapture(0, static_cast<uint32_t>(end));
      ++seen;
    }
  }
  b.RunTo(b.now + 1'000, 1'000);
  const std::vector<Message> exposures = b.Take(MessageType::kExposureReport);
  const std::vector<Message> pulses = b.Take(MessageType::kPulseReport);
  ASSERT_EQ(exposures.size(), seen);
  ASSERT_GE(pulses.size(), 25u);
  for (size_t k = 0; k < exposures.size(); ++k) {
    const proto::ExposureReport& e = exposures[k].exposure;
    EXPECT_EQ(e.seq, k);
    EXPECT_EQ(e.line, 0);
    EXPECT_EQ(e.start_us, b.lines.rises0[k] + 23);
    EXPECT_EQ(e.duration_us, 3'000 + k);
    if (k < pulses.size()) {  // T_k is the scheduled centre; the measured one 477 - k/2 µs early
      EXPECT_EQ(e.CentreUs() + 477, pulses[k].pulse.mcu_time_us + k / 2);
    }
  }
  EXPECT_EQ(b.app.meter().errors(), 0u);
  // An edge before the first rise of a run, or a start a period after the rise, is an error.
  b.app.OnCapture(0, static_cast<uint32_t>(b.lines.rises0.back() + 20'000));
  EXPECT_EQ(b.app.meter().errors(), 1u);
  b.app.OnOvercapture(0);
  EXPECT_EQ(b.app.meter().errors(), 2u);
  EXPECT_TRUE(b.app.meter().ExpectsStart(0));
}

}  // namespace
}  // namespace rigcal::trigger_core
