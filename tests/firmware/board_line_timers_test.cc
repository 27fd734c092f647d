// SPDX-License-Identifier: Apache-2.0
// Scheduler -> compare registers: the firmware core (TriggerApp) on the board's timer channels
// (Stm32LineTimers) against a fake STM32F405 register map. The test plays the timer hardware:
// it moves TIM2's count to the earliest armed compare, flags its channel and runs the compare
// interrupt's body, and checks the CCRx values and OCxM modes written against the timing rule
// (rise = T_k + phase offset - exposure / 2, fall = rise + width, T_k = t0 + floor(k 1e9 /
// rate)) for a sequence of ticks with phase offsets and exposures; also across the 32-bit
// counter's wrap, an interrupt too late for a fall, and the capture of an exposure.
#include <gtest/gtest.h>

#include <map>
#include <vector>

#include "fake_stm32.h"
#include "peripherals.h"
#include "pinout.h"
#include "rigcal/trigger_core/counter_extension.h"
#include "rigcal/trigger_core/trigger_app.h"
#include "rigcal/trigger_protocol/frame_codec.h"
#include "stm32_line_timers.h"

namespace rigcal::board {
namespace {

using testing::FakeStm32;
namespace proto = ::rigcal::trigger_protocol;
using namespace stm32;

// One compare the hardware made: the line, the count, and the level OCxM asked for.
struct Compare {
  int line;
  uint32_t ccr;
  bool high;
};

class Bench {
 public:
  explicit Bench(uint32_t preset) {
    InitTimers(83, preset);
    fake.SetCounter(preset);
    now = ext.Extend(preset);
    app.Boot(now);
  }
  void Command(const proto::Message& m) {
    uint8_t frame[proto::kMaxFrameSize];
    const size_t n = proto::EncodeFrame(m, frame, sizeof(frame));
    for (size_t i = 0; i < n; ++i) app.OnRxByte(frame[i], now);
  }
  void SetLine(uint8_t line, uint32_t width, int32_t offset, uint32_t exposure,
               proto::ExposureInput input = proto::ExposureInput::kNone) {
    proto::Message m;
    m.type = proto::MessageType::kSetLine;
    m.set_line = {1, line, 1, width, offset, exposure, input};
    Command(m);
  }
  void SetRate(uint32_t rate_mhz) {
    proto::Message m;
    m.type = proto::MessageType::kSetRate;
    m.set_rate = {2, rate_mhz};
    Command(m);
  }
  void Start() {
    proto::Message m;
    m.type = proto::MessageType::kStart;
    Command(m);
    t_start = now;
  }
  // The armed compare of `line` from the registers: its CCR and whether OCxM sets or clears.
  bool Armed(int line, uint32_t* ccr, bool* high) const {
    const LinePins& p = kLinePins[line];
    if ((fake.Peek(p.out_timer + kTimDier) & (1u << p.out_channel)) == 0) return false;
    const uint32_t ccmr = fake.Peek(p.out_timer + (p.out_channel <= 2 ? kTimCcmr1 : kTimCcmr2));
    const uint32_t ocm = (ccmr >> ((p.out_channel % 2 == 1 ? 0 : 8) + 4)) & 7;
    if (ocm != kOcmActiveOnMatch && ocm != kOcmInactiveOnMatch) return false;
    *ccr = fake.Peek(p.out_timer + kTimCcr1 + 4 * (p.out_channel - 1));
    *high = ocm == kOcmActiveOnMatch;
    return true;
  }
  // Plays the hardware until `count`: each armed compare in time order moves the count there,
  // flags the channel; the compare interrupt runs `latency_us` later.
  void RunUntil(uint64_t end_us, uint32_t latency_us = 0) {
    while (true) {
      int line = -1;
      uint32_t best_ccr = 0;
      bool best_high = false;
      uint64_t best_t = UINT64_MAX;
      for (int l = 0; l < proto::kMaxLines; ++l) {
        uint32_t ccr;
        bool high;
        if (!Armed(l, &ccr, &high)) continue;
        const uint64_t t = trigger_core::NearestTime(now, ccr);
        if (t < best_t) best_t = t, line = l, best_ccr = ccr, best_high = high;
      }
      if (line < 0 || best_t > end_us) break;
      compares.push_back({line, best_ccr, best_high});
      const LinePins& p = kLinePins[line];
      fake.SetFlag(p.out_timer, 1u << p.out_channel);
      MoveTo(best_t + latency_us);
      app_timers.ServiceCompareInterrupt(p.out_timer, &app);
      app.Poll(now);
    }
    MoveTo(end_us);
    app.Poll(now);
  }
  void MoveTo(uint64_t t_us) {
    if (t_us <= now) return;
    now = t_us;
    fake.SetCounter(static_cast<uint32_t>(t_us));
    ext.Extend(static_cast<uint32_t>(t_us));
  }
  std::vector<Compare> Of(int line) const {
    std::vector<Compare> out;
    for (const Compare& c : compares) {
      if (c.line == line) out.push_back(c);
    }
    return out;
  }
  std::vector<proto::Message> Sent(proto::MessageType type) {
    std::vector<proto::Message> out;
    uint8_t b;
    while (app.PopTx(&b)) {
      if (decoder.Push(b) == proto::DecodeEvent::kMessage) received.push_back(decoder.message());
    }
    for (const proto::Message& m : received) {
      if (m.type == type) out.push_back(m);
    }
    return out;
  }

  FakeStm32 fake;
  Stm32LineTimers app_timers;
  trigger_core::TriggerApp app{&app_timers};
  trigger_core::CounterExtension ext;
  proto::MessageDecoder decoder;
  std::vector<proto::Message> received;
  uint64_t now = 0;
  uint64_t t_start = 0;
  std::vector<Compare> compares;
};

// T_k of the test's own reckoning (messages.h / scheduler.h): t0 = start + 1000 µs arming lead
// + the largest exposure lead.
uint64_t TickUs(uint64_t t0, uint32_t rate_mhz, uint64_t k) {
  return t0 + k * 1'000'000'000ull / rate_mhz;
}

void ExpectLineCompares(const Bench& b, int line, uint64_t t0, uint32_t rate_mhz, int64_t offset,
                        uint32_t exposure, uint32_t width, size_t ticks) {
  const std::vector<Compare> c = b.Of(line);
  ASSERT_GE(c.size(), 2 * ticks) << "line " << line;
  for (size_t k = 0; k < ticks; ++k) {
    const uint64_t rise = TickUs(t0, rate_mhz, k) + offset - exposure / 2;
    EXPECT_EQ(c[2 * k].ccr, static_cast<uint32_t>(rise)) << "line " << line << " tick " << k;
    EXPECT_TRUE(c[2 * k].high);
    EXPECT_EQ(c[2 * k + 1].ccr, static_cast<uint32_t>(rise + width)) << "line " << line;
    EXPECT_FALSE(c[2 * k + 1].high);
  }
}

TEST(BoardLineTimers, CompareRegistersFollowTheTicksPhaseOffsetsAndExposures) {
  Bench b(5'000);
  b.SetRate(30'000);                // 30 Hz: 33333.3 µs, a fractional period
  b.SetLine(0, 200, 0, 10'000);     // TIM5 CH1: rises 5 ms before the tick
  b.SetLine(3, 300, 2'000, 4'000);  // TIM5 CH4: centre 2 ms after: rises at the tick
  b.SetLine(5, 50, 7'000, 0);       // TIM2 CH2: 7 ms after the tick
  b.Start();
  const uint64_t t0 = b.t_start + 1'000 + 5'000;
  b.RunUntil(t0 + 10 * 33'334);
  ExpectLineCompares(b, 0, t0, 30'000, 0, 10'000, 200, 10);
  ExpectLineCompares(b, 3, t0, 30'000, 2'000, 4'000, 300, 10);
  ExpectLineCompares(b, 5, t0, 30'000, 7'000, 0, 50, 10);
  EXPECT_TRUE(b.Of(1).empty());
  // The registers are the lines' own: TIM5_CCR1 (0x40000C34) for line 0, TIM2_CCR2 (0x40000038)
  // for line 5.
  EXPECT_FALSE(b.fake.ValuesWritten(0x40000C34).empty());
  EXPECT_FALSE(b.fake.ValuesWritten(0x40000038).empty());
  const std::vector<proto::Message> pulses = b.Sent(proto::MessageType::kPulseReport);
  ASSERT_GE(pulses.size(), 9u);
  for (size_t k = 0; k < 9; ++k) EXPECT_EQ(pulses[k].pulse.mcu_time_us, TickUs(t0, 30'000, k));
}

TEST(BoardLineTimers, ComparesCrossTheCountersWrap) {
  const uint32_t preset = 0xFFFF'FFFFu - 50'000;  // 50 ms before the wrap
  Bench b(preset);
  b.SetRate(100'000);           // 10 ms
  b.SetLine(4, 500, 0, 2'000);  // TIM2 CH1
  b.Start();
  const uint64_t t0 = b.t_start + 1'000 + 1'000;
  b.RunUntil(t0 + 100'000);
  ExpectLineCompares(b, 4, t0, 100'000, 0, 2'000, 500, 10);
  // CCR values are the low 32 bits: they wrapped to small numbers after 2^32.
  const std::vector<Compare> c = b.Of(4);
  EXPECT_GT(c.front().ccr, 0xFFFF'0000u);
  EXPECT_LT(c.back().ccr, 100'000u);
  const std::vector<proto::Message> pulses = b.Sent(proto::MessageType::kPulseReport);
  ASSERT_GE(pulses.size(), 9u);
  for (size_t k = 1; k < pulses.size(); ++k) {
    EXPECT_EQ(pulses[k].pulse.mcu_time_us - pulses[k - 1].pulse.mcu_time_us, 10'000u);
  }
  EXPECT_GT(pulses.back().pulse.mcu_time_us, uint64_t{1} << 32);
}

TEST(BoardLineTimers, AnInterruptTooLateForTheFallForcesTheLineLow) {
  Bench b(1'000);
  b.SetRate(100'000);
  b.SetLine(2, 25, 0, 0);  // TIM5 CH3, 25 µs wide
  b.Start();
  b.RunUntil(b.t_start + 1'001, /*latency_us=*/30);  // the interrupt 30 µs after the rise
  // The fall at rise + 25 was already past: OC3M forced inactive (100), the next rise armed.
  uint32_t ccr;
  bool high;
  ASSERT_TRUE(b.Armed(2, &ccr, &high));
  EXPECT_TRUE(high);
  EXPECT_EQ(ccr, static_cast<uint32_t>(b.t_start + 1'000 + 10'000));
  bool forced_low = false;
  for (uint32_t v : b.fake.ValuesWritten(kTim5 + kTimCcmr2)) {
    forced_low = forced_low || ((v >> 4) & 7) == kOcmForceInactive;
  }
  EXPECT_TRUE(forced_low);
  EXPECT_EQ(b.app.scheduler().late_edges(), 1u);
}

TEST(BoardLineTimers, CapturesOfAWiredLineBecomeAnExposureReport) {
  Bench b(0xFFFF'0000u);  // captures extended across TIM3's and TIM2's wraps
  b.SetRate(50'000);
  b.SetLine(1, 100, 0, 4'000, proto::ExposureInput::kActiveLow);  // TIM3 CH2 on PC7
  b.Start();
  // Active low: the first edge to capture is falling (CC2P = 1, CC2E = 1: CCER bits 7:4 = 0011).
  EXPECT_EQ((b.fake.Peek(kTim3 + kTimCcer) >> 4) & 0xF, 0x3u);
  const uint64_t rise = b.t_start + 1'000;
  b.RunUntil(rise + 1);
  // The camera starts exposing 31 µs after the rise, for 3210 µs.
  const uint64_t start = rise + 31, end = start + 3'210;
  b.MoveTo(start + 5);
  b.fake.Poke(kTim3 + kTimCcr1 + 4, static_cast<uint32_t>(start) & 0xFFFF);
  b.fake.SetFlag(kTim3, 1u << 2);
  b.app_timers.ServiceCaptureInterrupt(kTim3, &b.app);
  EXPECT_EQ((b.fake.Peek(kTim3 + kTimCcer) >> 4) & 0xF, 0x1u);  // now the rising end edge
  b.MoveTo(end + 7);
  b.fake.Poke(kTim3 + kTimCcr1 + 4, static_cast<uint32_t>(end) & 0xFFFF);
  b.fake.SetFlag(kTim3, 1u << 2);
  b.app_timers.ServiceCaptureInterrupt(kTim3, &b.app);
  b.app.Poll(b.now);
  const std::vector<proto::Message> e = b.Sent(proto::MessageType::kExposureReport);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e[0].exposure.seq, 0u);
  EXPECT_EQ(e[0].exposure.line, 1);
  EXPECT_EQ(e[0].exposure.start_us, start);
  EXPECT_EQ(e[0].exposure.duration_us, 3'210u);
}

}  // namespace
}  // namespace rigcal::board
