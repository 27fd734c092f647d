// SPDX-License-Identifier: Apache-2.0
// The cross-built trigger firmware on an emulated STM32F405 (qemu-system-arm -M netduinoplus2),
// over its USART1: boot Hello (with the clock status QEMU's missing RCC model leads to), command
// answers incl. every kind of refused value, then a run of pulse reports checked for continuity,
// exact MCU spacing and the rate seen by the host clock. Prints the pulse-rate error (ppm)
// against CLOCK_MONOTONIC and the firmware's health counters. A second image with its µs
// counter preset 4 s before 2^32 runs across the counter's wrap.
// Skips without the toolchain or QEMU (fails under CI=true). Label: firmware.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "qemu_process.h"
#include "rigcal/trigger_protocol/frame_codec.h"
#include "support/skip.h"

namespace rigcal::trigger_protocol {
namespace {

using testing::QemuFirmware;
using testing::SteadyNs;

struct Received {
  Message message;
  int64_t rx_ns;
};

class Link {
 public:
  explicit Link(QemuFirmware* qemu) : qemu_(qemu) {}

  void Send(const Message& m) {
    std::vector<uint8_t> f(kMaxFrameSize);
    f.resize(EncodeFrame(m, f.data(), f.size()));
    ASSERT_TRUE(qemu_->Write(f));
  }
  // Reads for up to `timeout_ms`, stopping early once `until` accepts a message.
  template <typename Pred>
  void ReadUntil(int timeout_ms, Pred until) {
    const int64_t deadline = SteadyNs() + int64_t{timeout_ms} * 1'000'000;
    while (SteadyNs() < deadline) {
      std::vector<uint8_t> bytes;
      qemu_->Read(&bytes, 20);
      const int64_t now = SteadyNs();
      bool done = false;
      for (uint8_t b : bytes) {
        if (decoder_.Push(b) == DecodeEvent::kMessage) {
          received.push_back({decoder_.message(), now});
          done = done || until(decoder_.message());
        }
      }
      if (done) return;
    }
  }
  // Sends a command and waits for its Ack or Nack (nullopt-like: type kHeartbeat if none).
  Message Ask(const Message& m, uint16_t id) {
    Send(m);
    Message answer;
    ReadUntil(3000, [&](const Message& r) {
      const bool mine = (r.type == MessageType::kAck && r.ack.command_id == id) ||
                        (r.type == MessageType::kNack && r.nack.command_id == id);
      if (mine) answer = r;
      return mine;
    });
    return answer;
  }
  std::vector<Received> received;
  const MessageDecoder& decoder() const { return decoder_; }

 private:
  QemuFirmware* qemu_;
  MessageDecoder decoder_;
};

Message Cmd(MessageType type, uint16_t id) {
  Message m;
  m.type = type;
  m.simple.command_id = id;
  return m;
}
Message Rate(uint16_t id, uint32_t mhz) {
  Message m;
  m.type = MessageType::kSetRate;
  m.set_rate = {id, mhz};
  return m;
}
Message Line(uint16_t id, uint8_t line, uint8_t enabled, uint32_t width, int32_t offset,
             uint32_t exposure) {
  Message m;
  m.type = MessageType::kSetLine;
  m.set_line = {id, line, enabled, width, offset, exposure};
  return m;
}

// Every pulse report in order, T_k exactly period * seq apart. Returns the seq gaps (ticks the
// firmware skipped: the caller compares them with the heartbeat's count).
uint32_t ExpectContinuousPulses(const std::vector<Received>& pulses, uint32_t period_us,
                                uint8_t mask) {
  uint32_t gaps = 0;
  for (size_t i = 1; i < pulses.size(); ++i) {
    const PulseReport& a = pulses[i - 1].message.pulse;
    const PulseReport& b = pulses[i].message.pulse;
    EXPECT_GT(b.seq, a.seq) << "out of order after seq " << a.seq;
    if (b.seq <= a.seq) return gaps;
    gaps += b.seq - a.seq - 1;
    EXPECT_EQ(b.mcu_time_us - a.mcu_time_us, uint64_t{period_us} * (b.seq - a.seq))
        << "seq " << b.seq;
    EXPECT_EQ(b.line_mask, mask);
  }
  return gaps;
}

void ExpectNack(const Message& a, NackReason reason, Field field, const char* what) {
  ASSERT_EQ(a.type, MessageType::kNack) << what << ": not refused";
  EXPECT_EQ(a.nack.reason, reason) << what << ": " << NackReasonName(a.nack.reason);
  EXPECT_EQ(a.nack.field, field) << what << ": " << FieldName(a.nack.field);
}

TEST(QemuFirmware, AnswersCommandsAndReportsEveryPulseAtItsRate) {
  if (const std::string missing = testing::QemuFirmwareMissing(); !missing.empty()) {
    RIGCAL_SKIP_MISSING() << missing;
  }
  // Flash and RAM of the image (arm-none-eabi-size -B, written next to it by the build).
  std::string elf = testing::TriggerFirmwareElf();
  std::ifstream size_file(elf.substr(0, elf.size() - 4) + ".size");
  std::string header;
  uint64_t text = 0, data = 0, bss = 0;
  ASSERT_TRUE(std::getline(size_file, header) && (size_file >> text >> data >> bss))
      << "no arm-none-eabi-size output beside " << elf;
  std::printf(
      "firmware image: flash %llu bytes (text %llu + data %llu), RAM %llu bytes "
      "(data %llu + bss %llu, incl. the 4096-byte stack reserve)\n",
      static_cast<unsigned long long>(text + data), static_cast<unsigned long long>(text),
      static_cast<unsigned long long>(data), static_cast<unsigned long long>(data + bss),
      static_cast<unsigned long long>(data), static_cast<unsigned long long>(bss));
  EXPECT_LT(text + data, 1024u * 1024u);
  EXPECT_LT(data + bss, 128u * 1024u);

  QemuFirmware qemu;
  std::string error;
  ASSERT_TRUE(qemu.Start(QemuFirmware::Serial::kStdio, &error)) << error;
  Link link(&qemu);

  // Boot: a Hello, then heartbeats.
  link.ReadUntil(5000, [](const Message& m) { return m.type == MessageType::kHeartbeat; });
  ASSERT_FALSE(link.received.empty())
      << "no frame from the firmware within 5 s (exit " << qemu.ExitedWith() << ")";
  EXPECT_EQ(link.received[0].message.type, MessageType::kHello);
  const Hello& hello = link.received[0].message.hello;
  EXPECT_EQ(hello.max_lines, kMaxLines);
  // QEMU models no RCC (its registers read 0): the same image as on a board takes the HSE
  // timeout and the PLL timeout, and measures QEMU's 1 GHz timer clock instead of 84 MHz.
  std::printf("firmware Hello under QEMU: clock_status 0x%02x, crystal %u MHz\n",
              hello.clock_status, hello.hse_mhz);
  EXPECT_EQ(hello.clock_status, kClockHseFallback | kClockPllFailed | kClockTimerMeasured);
  EXPECT_GT(hello.hse_mhz, 0);

  // Refused values, each with its reason and field; nothing of them is applied.
  ExpectNack(link.Ask(Rate(1, 50), 1), NackReason::kOutOfRange, Field::kRate, "rate 0.05 Hz");
  ExpectNack(link.Ask(Rate(2, 1'000'000), 2), NackReason::kOutOfRange, Field::kRate, "1 kHz");
  ExpectNack(link.Ask(Line(3, 9, 1, 100, 0, 0), 3), NackReason::kOutOfRange, Field::kLine,
             "line 9");
  ExpectNack(link.Ask(Line(4, 0, 1, 60'000, 0, 0), 4), NackReason::kOutOfRange, Field::kWidth,
             "width > period");
  ExpectNack(link.Ask(Line(5, 0, 1, 100, 0, 2'000'000), 5), NackReason::kOutOfRange,
             Field::kExposure, "exposure 2 s");
  ExpectNack(link.Ask(Line(6, 0, 1, 100, 49'000, 4'000), 6), NackReason::kOutOfRange,
             Field::kPhaseOffset, "offset + exposure / 2 > period");
  ExpectNack(link.Ask(Cmd(MessageType::kStart, 7), 7), NackReason::kNoLinesEnabled, Field::kLine,
             "start without lines");

  // 100 Hz on lines 0 and 2 (exposure-centred, 4 ms exposure), then a second of a running
  // trigger that refuses a rate change.
  const uint32_t rate_mhz = 100'000;
  ASSERT_EQ(link.Ask(Rate(10, rate_mhz), 10).type, MessageType::kAck);
  ASSERT_EQ(link.Ask(Line(11, 0, 1, 500, 0, 4'000), 11).type, MessageType::kAck);
  ASSERT_EQ(link.Ask(Line(12, 2, 1, 500, 1'000, 0), 12).type, MessageType::kAck);
  link.received.clear();
  ASSERT_EQ(link.Ask(Cmd(MessageType::kStart, 13), 13).type, MessageType::kAck);
  ExpectNack(link.Ask(Rate(14, 10'000), 14), NackReason::kBusy, Field::kNone, "rate while running");
  const double run_s = 4.0;
  link.ReadUntil(static_cast<int>(run_s * 1000), [](const Message&) { return false; });
  ASSERT_EQ(link.Ask(Cmd(MessageType::kStop, 15), 15).type, MessageType::kAck);
  link.ReadUntil(300, [](const Message&) { return false; });  // the last heartbeat

  std::vector<Received> pulses;
  const Heartbeat* last_hb = nullptr;
  for (const Received& r : link.received) {
    if (r.message.type == MessageType::kPulseReport) pulses.push_back(r);
    if (r.message.type == MessageType::kHeartbeat) last_hb = &r.message.heartbeat;
  }
  ASSERT_GE(pulses.size(), static_cast<size_t>(0.8 * run_s * 100)) << "too few pulse reports";
  // Continuity and exact MCU spacing: T_k = t0 + k * 10 ms for seq k. A gap in seq is allowed
  // only for a tick the firmware skipped (the emulated MCU stalled for more than a period while
  // the host was busy) and counted in its heartbeat, so every lost report is accounted for.
  ASSERT_NE(last_hb, nullptr);
  const uint32_t period_us = PeriodUs(rate_mhz);
  uint32_t gaps = pulses[0].message.pulse.seq;  // the first run starts at seq 0
  gaps += ExpectContinuousPulses(pulses, period_us, 0x05);
  EXPECT_EQ(gaps, last_hb->skipped_ticks) << "a report was lost, not skipped by the firmware";
  EXPECT_LT(gaps, pulses.size() / 10) << "the emulated MCU stalled for more than 10% of the ticks";
  // Rate against the host clock: least-squares slope of receive time over seq (the serial and
  // emulation delay jitter averages out over the run).
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(pulses.size());
  const int64_t y0 = pulses[0].rx_ns;
  const uint32_t seq0 = pulses[0].message.pulse.seq;
  for (size_t i = 0; i < pulses.size(); ++i) {
    const double x = static_cast<double>(pulses[i].message.pulse.seq - seq0);
    const double y = static_cast<double>(pulses[i].rx_ns - y0) * 1e-9;
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  const double period_s = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double rate_hz = 1.0 / period_s;
  const double rate_error_ppm = (rate_hz / (rate_mhz * 1e-3) - 1.0) * 1e6;
  double max_resid_ms = 0.0;
  const double icpt = (sy - period_s * sx) / n;
  for (size_t i = 0; i < pulses.size(); ++i) {
    const double y = static_cast<double>(pulses[i].rx_ns - y0) * 1e-9;
    const double x = static_cast<double>(pulses[i].message.pulse.seq - seq0);
    max_resid_ms = std::max(max_resid_ms, std::abs(y - icpt - period_s * x) * 1e3);
  }
  std::printf(
      "firmware under QEMU: %zu pulse reports at %.6f Hz host clock (nominal %.3f Hz): "
      "rate error %+.0f ppm; receive-time residual max %.2f ms\n",
      pulses.size(), rate_hz, rate_mhz * 1e-3, rate_error_ppm, max_resid_ms);
  // A broken time base (wrong SysTick reload, lost milliseconds) is off by >= 1e-3; the
  // emulator's clock follows the host's, so the residual error is the serial jitter / run time.
  EXPECT_LT(std::abs(rate_error_ppm), 5'000.0);
  std::printf(
      "firmware health: late_edges %u (of %zu edges; > %u us late under emulation) "
      "skipped_ticks %u rx_errors %u tx_dropped %u; host decoder errors %u\n",
      last_hb->late_edges, 4 * (pulses.size() + gaps), 50u, last_hb->skipped_ticks,
      last_hb->rx_errors, last_hb->tx_dropped, link.decoder().stats().Errors());
  EXPECT_EQ(last_hb->running, 0);
  EXPECT_EQ(last_hb->next_seq, pulses.back().message.pulse.seq + 1);
  EXPECT_EQ(last_hb->rx_errors, 0);
  EXPECT_EQ(last_hb->tx_dropped, 0);
  EXPECT_EQ(link.decoder().stats().Errors(), 0u);
  EXPECT_EQ(qemu.ExitedWith(), -1) << "the firmware ended (a fault exits through semihosting)";
}

TEST(QemuFirmware, RunsAcrossTheCounterWrapWithAPresetCounter) {
  const std::string elf = testing::TriggerFirmwareWrapTestElf();
  if (const std::string missing = testing::QemuFirmwareMissing(elf); !missing.empty()) {
    RIGCAL_SKIP_MISSING() << missing;
  }
  QemuFirmware qemu;
  std::string error;
  ASSERT_TRUE(qemu.Start(QemuFirmware::Serial::kStdio, &error, elf)) << error;
  Link link(&qemu);
  link.ReadUntil(5000, [](const Message& m) { return m.type == MessageType::kHeartbeat; });
  ASSERT_FALSE(link.received.empty()) << "no frame within 5 s (exit " << qemu.ExitedWith() << ")";
  ASSERT_EQ(link.received[0].message.type, MessageType::kHello);
  const Hello hello = link.received[0].message.hello;
  constexpr uint64_t kWrap = uint64_t{1} << 32;
  EXPECT_NE(hello.clock_status & kClockTestImage, 0) << "the test image says it is one";
  // The counter was preset 4 s before the wrap; the boot (clock timeouts, the 10 ms timer
  // measurement) takes well under 2 s.
  EXPECT_GE(hello.mcu_time_us, kWrap - 4'000'000);
  EXPECT_LT(hello.mcu_time_us, kWrap - 2'000'000);
  const uint32_t rate_mhz = 100'000;
  ASSERT_EQ(link.Ask(Rate(1, rate_mhz), 1).type, MessageType::kAck);
  ASSERT_EQ(link.Ask(Line(2, 0, 1, 500, 0, 2'000), 2).type, MessageType::kAck);
  link.received.clear();
  ASSERT_EQ(link.Ask(Cmd(MessageType::kStart, 3), 3).type, MessageType::kAck);
  link.ReadUntil(6'000, [](const Message&) { return false; });  // across the wrap
  ASSERT_EQ(link.Ask(Cmd(MessageType::kStop, 4), 4).type, MessageType::kAck);
  link.ReadUntil(300, [](const Message&) { return false; });

  std::vector<Received> pulses;
  std::vector<uint64_t> heartbeat_us;
  const Heartbeat* last_hb = nullptr;
  for (const Received& r : link.received) {
    if (r.message.type == MessageType::kPulseReport) pulses.push_back(r);
    if (r.message.type == MessageType::kHeartbeat) {
      heartbeat_us.push_back(r.message.heartbeat.mcu_time_us);
      last_hb = &r.message.heartbeat;
    }
  }
  ASSERT_NE(last_hb, nullptr);
  ASSERT_GE(pulses.size(), 300u);
  const uint64_t first = pulses.front().message.pulse.mcu_time_us;
  const uint64_t last = pulses.back().message.pulse.mcu_time_us;
  std::printf("wrap image: pulses %zu, T from 2^32 - %llu us to 2^32 + %llu us; %zu heartbeats\n",
              pulses.size(), static_cast<unsigned long long>(kWrap - first),
              static_cast<unsigned long long>(last - kWrap), heartbeat_us.size());
  EXPECT_LT(first, kWrap);
  EXPECT_GT(last, kWrap + 1'000'000) << "the run did not cross the counter's wrap";
  uint32_t gaps = pulses[0].message.pulse.seq;
  gaps += ExpectContinuousPulses(pulses, PeriodUs(rate_mhz), 0x01);
  EXPECT_EQ(gaps, last_hb->skipped_ticks);
  for (size_t i = 1; i < heartbeat_us.size(); ++i) {
    EXPECT_GT(heartbeat_us[i], heartbeat_us[i - 1]) << "MCU time went back at heartbeat " << i;
    EXPECT_LT(heartbeat_us[i] - heartbeat_us[i - 1], 1'000'000u) << "MCU time jumped";
  }
  EXPECT_EQ(link.decoder().stats().Errors(), 0u);
  EXPECT_EQ(qemu.ExitedWith(), -1) << "the firmware ended (a fault exits through semihosting)";
}

}  // namespace
}  // namespace rigcal::trigger_protocol
