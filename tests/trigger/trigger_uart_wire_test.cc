// SPDX-License-Identifier: Apache-2.0
// The UART wire time of the trigger reports: the MCU stamps a message before its first byte
// leaves, the host sees it once the last byte is in. TriggerLink stamps every message earlier
// by the wire time of its frame and of the bytes read after it (set_uart_byte_ns); the clock
// map then needs no constant correction per message length. Prints the mapped-time bias with
// and without it at 115200 baud.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>
#include <random>
#include <vector>

#include "rigcal/trigger/serial_port.h"
#include "rigcal/trigger/trigger_link.h"
#include "rigcal/trigger/trigger_matcher.h"
#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::trigger {
namespace {

namespace proto = trigger_protocol;

constexpr double kByteNs = 1e10 / 115200;  // 10 bits per byte

// Hands out scripted reads: each returns its bytes at its host time.
class ScriptedStream final : public ByteStream {
 public:
  struct Chunk {
    int64_t at_ns;
    std::vector<uint8_t> bytes;
  };
  explicit ScriptedStream(std::deque<Chunk> chunks) : chunks_(std::move(chunks)) {}
  Expected<size_t> Read(uint8_t* data, size_t size, int) override {
    if (chunks_.empty()) return size_t{0};
    Chunk c = std::move(chunks_.front());
    chunks_.pop_front();
    now_ns_ = c.at_ns;
    const size_t n = std::min(size, c.bytes.size());
    std::copy(c.bytes.begin(), c.bytes.begin() + static_cast<long>(n), data);
    return n;
  }
  Status Write(const uint8_t*, size_t) override { return Status::Ok(); }
  int64_t NowNs() const override { return now_ns_; }
  bool empty() const { return chunks_.empty(); }

 private:
  std::deque<Chunk> chunks_;
  int64_t now_ns_ = 0;
};

std::vector<uint8_t> Pulse(uint32_t seq, uint64_t mcu_us) {
  proto::Message m;
  m.type = proto::MessageType::kPulseReport;
  m.pulse = {1, seq, mcu_us};
  std::vector<uint8_t> frame(proto::kMaxFrameSize);
  frame.resize(proto::EncodeFrame(m, frame.data(), frame.size()));
  return frame;
}

std::vector<uint8_t> Heartbeat(uint64_t mcu_us) {
  proto::Message m;
  m.type = proto::MessageType::kHeartbeat;
  m.heartbeat.mcu_time_us = mcu_us;
  m.heartbeat.running = 1;
  std::vector<uint8_t> frame(proto::kMaxFrameSize);
  frame.resize(proto::EncodeFrame(m, frame.data(), frame.size()));
  return frame;
}

int64_t Wire(size_t bytes) { return std::llround(kByteNs * static_cast<double>(bytes)); }

std::vector<uint8_t> Concat(std::vector<uint8_t> a, const std::vector<uint8_t>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

std::vector<TriggerEvent> ReadAll(ScriptedStream* raw, std::unique_ptr<ScriptedStream> stream,
                                  bool uart) {
  TriggerLink link(std::move(stream));
  if (uart) link.set_uart_byte_ns(kByteNs);
  std::vector<TriggerEvent> events;
  while (!raw->empty()) EXPECT_TRUE(link.Poll(0, &events).ok());
  return events;
}

TEST(TriggerUartWire, AMessageIsStampedWhenItsFirstByteLeft) {
  const std::vector<uint8_t> pulse = Pulse(7, 1000);
  const std::vector<uint8_t> beat = Heartbeat(2000);
  ASSERT_GT(pulse.size(), 10u);
  ASSERT_NE(pulse.size(), beat.size());
  const int64_t t0 = 5'000'000'000;
  // One frame per read, the read returning as its last byte arrives.
  {
    auto stream = std::make_unique<ScriptedStream>(
        std::deque<ScriptedStream::Chunk>{{t0 + Wire(pulse.size()), pulse}});
    ScriptedStream* raw = stream.get();
    const auto events = ReadAll(raw, std::move(stream), true);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].rx_ns, t0);
  }
  // Without a UART (USB CDC, a pty) the receive time stays.
  {
    auto stream = std::make_unique<ScriptedStream>(
        std::deque<ScriptedStream::Chunk>{{t0 + Wire(pulse.size()), pulse}});
    ScriptedStream* raw = stream.get();
    const auto events = ReadAll(raw, std::move(stream), false);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].rx_ns, t0 + Wire(pulse.size()));
  }
  // Two frames back to back in one read: the first crossed the wire before the second.
  {
    const int64_t t1 = t0 + Wire(pulse.size());  // the heartbeat leaves when the pulse is out
    auto stream = std::make_unique<ScriptedStream>(
        std::deque<ScriptedStream::Chunk>{{t1 + Wire(beat.size()), Concat(pulse, beat)}});
    ScriptedStream* raw = stream.get();
    const auto events = ReadAll(raw, std::move(stream), true);
    ASSERT_EQ(events.size(), 2u);
    EXPECT_EQ(events[0].rx_ns, t0);
    EXPECT_EQ(events[1].rx_ns, t1);
  }
  // A frame split over two reads: its bytes of the first read count too.
  {
    const std::vector<uint8_t> head(pulse.begin(), pulse.begin() + 5);
    const std::vector<uint8_t> tail(pulse.begin() + 5, pulse.end());
    auto stream = std::make_unique<ScriptedStream>(
        std::deque<ScriptedStream::Chunk>{{t0 + Wire(5), head}, {t0 + Wire(pulse.size()), tail}});
    ScriptedStream* raw = stream.get();
    const auto events = ReadAll(raw, std::move(stream), true);
    ASSERT_EQ(events.size(), 1u);
    EXPECT_EQ(events[0].rx_ns, t0);
  }
}

// 20 Hz pulses and 10 Hz heartbeats (longer frames) over 115200 baud, then a USB-like delay of
// 0-2 ms: the mapped pulse times are unbiased with the wire time taken off, and late by about a
// pulse report's wire time (1.6 ms) without.
TEST(TriggerUartWire, TheClockMapIsUnbiasedWithTheWireTimeTakenOff) {
  const int64_t boot_ns = 3'000'000'000;
  std::mt19937_64 rng(5);
  std::deque<ScriptedStream::Chunk> chunks;
  std::vector<uint64_t> pulse_us;
  for (int k = 0; k < 1200; ++k) {  // 60 s
    const uint64_t t_us = 1'000'000 + static_cast<uint64_t>(k) * 50'000;
    const auto delay = static_cast<int64_t>(rng() % 2'000'001);
    const std::vector<uint8_t> pulse = Pulse(static_cast<uint32_t>(k), t_us);
    chunks.push_back(
        {boot_ns + static_cast<int64_t>(t_us) * 1000 + Wire(pulse.size()) + delay, pulse});
    pulse_us.push_back(t_us);
    if (k % 2 == 0) {
      const uint64_t h_us = t_us + 25'000;
      const std::vector<uint8_t> beat = Heartbeat(h_us);
      chunks.push_back({boot_ns + static_cast<int64_t>(h_us) * 1000 + Wire(beat.size()) +
                            static_cast<int64_t>(rng() % 2'000'001),
                        beat});
    }
  }
  double bias_us[2] = {0, 0};
  double rms_us[2] = {0, 0};
  for (int uart = 0; uart < 2; ++uart) {
    auto stream = std::make_unique<ScriptedStream>(chunks);
    ScriptedStream* raw = stream.get();
    const std::vector<TriggerEvent> events = ReadAll(raw, std::move(stream), uart == 1);
    TriggerMatcher matcher;
    for (const TriggerEvent& e : events) matcher.OnMessage(e.message, e.rx_ns);
    double sum = 0, sum2 = 0;
    for (uint64_t t_us : pulse_us) {
      const double error_us =
          static_cast<double>(*matcher.MapMcuTime(t_us) - (boot_ns + int64_t(t_us) * 1000)) * 1e-3;
      sum += error_us;
      sum2 += error_us * error_us;
    }
    bias_us[uart] = sum / static_cast<double>(pulse_us.size());
    rms_us[uart] = std::sqrt(sum2 / static_cast<double>(pulse_us.size()));
  }
  std::printf(
      "mapped pulse time - true pulse time over 115200 baud + 0-2 ms delay: without the wire "
      "time %.1f us mean (%.1f us RMS), with it %.1f us mean (%.1f us RMS); a pulse report "
      "takes %.0f us on the wire\n",
      bias_us[0], rms_us[0], bias_us[1], rms_us[1], kByteNs * Pulse(0, 0).size() * 1e-3);
  EXPECT_GT(bias_us[0], 1000.0);  // late by about the wire time
  EXPECT_LT(std::abs(bias_us[1]), 50.0);
  EXPECT_LT(rms_us[1], 50.0);
}

}  // namespace
}  // namespace rigcal::trigger
