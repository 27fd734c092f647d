// SPDX-License-Identifier: Apache-2.0
// The trigger scheduler (firmware/core) on ideal compare timers (IdealLineTimers): tick times,
// exposure-centred rises, phase offsets, widths, reports (order, seq, never before the tick or a
// rise), stop/start, edges the compare interrupt re-armed too late, and skipped ticks.
#include "rigcal/trigger_core/scheduler.h"

#include <gtest/gtest.h>

#include <vector>

#include "rigcal/trigger_core/ideal_line_timers.h"

namespace rigcal::trigger_core {
namespace {

// Records every level change and report, with the time it happened.
class IdealRun final : public EdgeSink, public CompareHandler {
 public:
  explicit IdealRun(Scheduler* s) : s_(s), timers(this) {}
  void OnEdge(const LineEdge& e) override { edges.push_back(e); }
  // The compare interrupt: `latency_us` after the edge, and not before `held_until_us`.
  void OnCompare(int line) override {
    timers.set_now(std::max(timers.now() + latency_us, held_until_us));
    s_->OnCompare(line, &timers);
  }
  bool Start(uint64_t now_us) {
    timers.set_now(now_us);
    return s_->Start(now_us, &timers);
  }
  // An ideal board until `end_us`: every edge at its time, the main loop at every report's time.
  void RunUntil(uint64_t end_us) {
    while (true) {
      const uint64_t next = std::min(timers.NextEdgeUs(), s_->NextReportUs());
      if (next > end_us) break;
      timers.RunUntil(next, this);
      Drain(std::max(next, timers.now()));
    }
    timers.RunUntil(end_us, this);
  }
  void Drain(uint64_t now_us) {
    proto::PulseReport r;
    while (s_->PopReport(now_us, &r)) {
      reports.push_back(r);
      report_times.push_back(now_us);
    }
  }
  std::vector<LineEdge> Edges(int line, bool high) const {
    std::vector<LineEdge> out;
    for (const LineEdge& e : edges) {
      if (e.line == line && e.high == high) out.push_back(e);
    }
    return out;
  }

  Scheduler* s_;
  IdealLineTimers timers;
  uint64_t latency_us = 0;
  uint64_t held_until_us = 0;
  std::vector<LineEdge> edges;
  std::vector<proto::PulseReport> reports;
  std::vector<uint64_t> report_times;
};

TriggerConfig OneLine(uint32_t rate_mhz, uint32_t width_us) {
  TriggerConfig c;
  c.rate_mhz = rate_mhz;
  c.lines[0].enabled = true;
  c.lines[0].width_us = width_us;
  return c;
}

constexpr uint64_t kLead = Scheduler::kArmLeadUs;

TEST(Scheduler, OneLineRisesAtEveryTickAndReportsIt) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(20'000, 100)));  // 20 Hz
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(1'000));
  r.RunUntil(1'000 + kLead + 1'000'000 - 1);  // one second
  const std::vector<LineEdge> rises = r.Edges(0, true);
  const std::vector<LineEdge> falls = r.Edges(0, false);
  ASSERT_EQ(rises.size(), 20u);
  ASSERT_EQ(falls.size(), 20u);
  ASSERT_EQ(r.reports.size(), 20u);
  for (size_t k = 0; k < rises.size(); ++k) {
    EXPECT_EQ(rises[k].t_us, 1'000 + kLead + 50'000 * k);
    EXPECT_EQ(falls[k].t_us, rises[k].t_us + 100);
    EXPECT_EQ(r.reports[k].seq, k);
    EXPECT_EQ(r.reports[k].mcu_time_us, rises[k].t_us);
    EXPECT_EQ(r.reports[k].line_mask, 0x01);
    EXPECT_EQ(r.report_times[k], rises[k].t_us);
  }
  EXPECT_EQ(s.late_edges(), 0u);
  EXPECT_EQ(s.next_seq(), 20u);
}

TEST(Scheduler, ExposureCentredRisesWithPhaseOffsets) {
  TriggerConfig c;
  c.rate_mhz = 10'000;                     // 100 ms
  c.lines[0] = {true, 200, 0, 10'000};     // rises 5 ms before the tick
  c.lines[3] = {true, 300, 2'000, 4'000};  // centre 2 ms after the tick: rises at the tick
  c.lines[5] = {true, 50, 7'000, 0};       // rises 7 ms after the tick
  Scheduler s;
  ASSERT_TRUE(s.Configure(c));
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(1'000));
  r.RunUntil(1'000'000);
  const uint64_t t0 = 1'000 + kLead + 5'000;  // the largest lead: the first rise kLead after start
  ASSERT_GE(r.reports.size(), 9u);
  for (size_t k = 0; k < 9; ++k) {
    const uint64_t tk = t0 + 100'000 * k;
    EXPECT_EQ(r.Edges(0, true)[k].t_us, tk - 5'000);
    EXPECT_EQ(r.Edges(0, false)[k].t_us, tk - 5'000 + 200);
    EXPECT_EQ(r.Edges(3, true)[k].t_us, tk);
    EXPECT_EQ(r.Edges(3, false)[k].t_us, tk + 300);
    EXPECT_EQ(r.Edges(5, true)[k].t_us, tk + 7'000);
    // The report carries T_k and leaves after every rise of its tick.
    EXPECT_EQ(r.reports[k].mcu_time_us, tk);
    EXPECT_EQ(r.reports[k].line_mask, (1u << 0) | (1u << 3) | (1u << 5));
    EXPECT_EQ(r.report_times[k], tk + 7'000);
  }
  EXPECT_TRUE(r.Edges(1, true).empty());
}

TEST(Scheduler, ReportsWaitForTheTickWhenEveryLineRisesBeforeIt) {
  Scheduler s;
  TriggerConfig c = OneLine(100'000, 100);
  c.lines[0].exposure_us = 6'000;  // rises 3 ms before T_k
  ASSERT_TRUE(s.Configure(c));
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(0));
  r.RunUntil(50'000);
  ASSERT_EQ(r.reports.size(), 5u);
  for (size_t k = 0; k < 5; ++k) {
    EXPECT_EQ(r.reports[k].mcu_time_us, kLead + 3'000 + 10'000 * k);
    EXPECT_EQ(r.report_times[k], r.reports[k].mcu_time_us);  // not at the rise, 3 ms earlier
  }
}

TEST(Scheduler, FractionalPeriodsDoNotAccumulateRoundingError) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(30'000, 100)));  // 30 Hz: 33333.3 µs
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(0));
  r.RunUntil(kLead + 100'000'000);  // 100 s
  ASSERT_EQ(r.reports.size(), 3001u);
  EXPECT_EQ(r.reports[3000].mcu_time_us, kLead + 100'000'000u);  // exactly 3000 periods
  EXPECT_EQ(r.reports[1].mcu_time_us, kLead + 33'333u);
  EXPECT_EQ(r.reports[2].mcu_time_us, kLead + 66'666u);
  for (size_t k = 1; k < r.reports.size(); ++k) {
    const uint64_t d = r.reports[k].mcu_time_us - r.reports[k - 1].mcu_time_us;
    ASSERT_TRUE(d == 33'333u || d == 33'334u) << k;
    ASSERT_EQ(r.reports[k].mcu_time_us, s.TickTimeUs(k)) << "incremental tick clock drifted";
  }
}

TEST(Scheduler, StopReleasesTheLinesAndSequenceNumbersContinueAfterRestart) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(100'000, 5'000)));  // 100 Hz, 5 ms wide
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(0));
  r.RunUntil(kLead + 32'000);  // ticks 0..3; line high since 30 ms
  ASSERT_EQ(r.reports.size(), 4u);
  ASSERT_TRUE(r.edges.back().high);
  EXPECT_FALSE(s.Start(32'000, &r.timers));  // already running
  s.Stop(&r.timers);
  EXPECT_FALSE(r.edges.back().high);
  EXPECT_EQ(r.timers.NextEdgeUs(), UINT64_MAX);  // nothing armed
  r.RunUntil(500'000);
  EXPECT_EQ(r.reports.size(), 4u);
  EXPECT_EQ(s.next_seq(), 4u);
  ASSERT_TRUE(r.Start(1'000'000));
  r.RunUntil(1'000'000 + kLead + 25'000);
  ASSERT_EQ(r.reports.size(), 7u);
  EXPECT_EQ(r.reports[4].seq, 4u);
  EXPECT_EQ(r.reports[4].mcu_time_us, 1'000'000u + kLead);
  EXPECT_EQ(r.reports[6].seq, 6u);
}

TEST(Scheduler, ConfigurationIsRefusedWhileRunningOrInvalid) {
  Scheduler s;
  EXPECT_FALSE(s.Configure(OneLine(20'000, 50'000)));  // width == period
  EXPECT_FALSE(s.Configure(OneLine(20'000, 49'976)));  // gap to the next rise below 25 µs
  EXPECT_FALSE(s.Configure(OneLine(20'000, 24)));      // below the minimum width
  IdealRun r(&s);
  EXPECT_FALSE(r.Start(0));  // default config has no line enabled
  ASSERT_TRUE(s.Configure(OneLine(20'000, 49'975)));
  ASSERT_TRUE(r.Start(0));
  EXPECT_FALSE(s.Configure(OneLine(10'000, 100)));
  EXPECT_EQ(s.config().rate_mhz, 20'000u);
}

TEST(Scheduler, AFallArmedTooLateIsDrivenAtOnceAndCounted) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(100'000, 100)));  // 10 ms period, 100 µs wide
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(0));
  r.latency_us = 200;  // the interrupt after the first rise comes 200 µs late
  r.RunUntil(kLead + 1);
  r.latency_us = 0;
  r.RunUntil(kLead + 25'000);
  const std::vector<LineEdge> rises = r.Edges(0, true), falls = r.Edges(0, false);
  ASSERT_EQ(rises.size(), 3u);
  EXPECT_EQ(rises[0].t_us, kLead);        // the hardware made the rise on time
  EXPECT_EQ(falls[0].t_us, kLead + 200);  // the fall when the interrupt could drive it
  EXPECT_EQ(falls[1].t_us, kLead + 10'100);
  EXPECT_EQ(s.late_edges(), 1u);
  ASSERT_EQ(r.reports.size(), 3u);  // the tick happened: reported
  EXPECT_EQ(s.skipped_ticks(), 0u);
}

TEST(Scheduler, ARiseThatCannotBeArmedSkipsTicksForEveryLine) {
  TriggerConfig c = OneLine(100'000, 100);  // 10 ms period
  c.lines[1] = {true, 100, 3'000, 0};       // line 1 rises 3 ms after line 0
  Scheduler s;
  ASSERT_TRUE(s.Configure(c));
  IdealRun r(&s);
  ASSERT_TRUE(r.Start(0));
  r.RunUntil(kLead + 50);  // tick 0's rise on line 0
  // Every interrupt is held off until 45 ms (a halted core): line 0's fall is made by the
  // hardware but its next rise cannot be armed in time; line 1 rises on time, its fall is late.
  // Ticks 1..4 are skipped on both lines.
  r.held_until_us = kLead + 45'000;
  r.RunUntil(kLead + 100'000);
  ASSERT_FALSE(r.reports.empty());
  std::vector<uint32_t> seqs;
  for (const proto::PulseReport& p : r.reports) seqs.push_back(p.seq);
  EXPECT_EQ(seqs.front(), 0u);
  EXPECT_EQ(seqs[1], 5u) << "ticks 1..4 lie before the interrupt came back";
  for (size_t i = 2; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], seqs[i - 1] + 1);
  EXPECT_EQ(s.skipped_ticks(), 4u);
  for (const proto::PulseReport& p : r.reports) {
    EXPECT_EQ(p.mcu_time_us, s.TickTimeUs(p.seq));  // reports keep their exact tick times
  }
  // Every rise that happened is a compare time; none between the stall and tick 5.
  for (int line = 0; line < 2; ++line) {
    for (const LineEdge& e : r.Edges(line, true)) {
      EXPECT_TRUE(e.t_us == kLead + line * 3'000 || e.t_us >= s.TickTimeUs(5)) << e.t_us;
    }
  }
}

TEST(TriggerConfig, RangeChecksNameTheField) {
  EXPECT_EQ(CheckRate(99).field, proto::Field::kRate);
  EXPECT_TRUE(CheckRate(100).ok());
  EXPECT_TRUE(CheckRate(400'000).ok());
  EXPECT_EQ(CheckRate(400'001).field, proto::Field::kRate);
  LineConfig line{true, 0, 0, 0};
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kWidth);
  line.width_us = 49'975;
  EXPECT_TRUE(CheckLine(line, 20'000).ok());
  line.width_us = 49'976;
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kWidth);
  line.width_us = 100;
  line.exposure_us = 1'000'001;
  EXPECT_EQ(CheckLine(line, 100).field, proto::Field::kExposure);
  line.exposure_us = 20'000;
  line.phase_offset_us = -39'999;  // 39999 + 20000 / 2 < 50000
  EXPECT_TRUE(CheckLine(line, 20'000).ok());
  line.phase_offset_us = -40'000;
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kPhaseOffset);
  line.phase_offset_us = 0;
  line.exposure_input = static_cast<proto::ExposureInput>(3);
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kExposureInput);
  EXPECT_EQ(CheckHeartbeat(5).field, proto::Field::kHeartbeatPeriod);
  EXPECT_TRUE(CheckHeartbeat(0).ok());
  EXPECT_TRUE(CheckHeartbeat(10'000).ok());
  EXPECT_FALSE(CheckHeartbeat(10'001).ok());
}

TEST(TriggerConfig, EveryConfigurationFitsTheLink) {
  // 115200 baud = 11520 B/s, 90 % usable: a pulse report is 19 bytes, an exposure report 23, a
  // heartbeat 27 (version, type, body, CRC, COBS byte, delimiter).
  EXPECT_EQ(proto::FrameBytes(proto::MessageType::kPulseReport), 19u);
  EXPECT_EQ(proto::FrameBytes(proto::MessageType::kExposureReport), 23u);
  EXPECT_EQ(proto::FrameBytes(proto::MessageType::kHeartbeat), 27u);
  EXPECT_TRUE(proto::FitsLink(400'000, 0, 10));    // 7600 + 2700 = 10300 <= 10368
  EXPECT_FALSE(proto::FitsLink(400'000, 1, 100));  // 16800 + 270
  EXPECT_TRUE(proto::FitsLink(45'000, 8, 100));    // 45 * 203 + 270 = 9405
  EXPECT_FALSE(proto::FitsLink(51'000, 8, 100));   // 51 * 203 + 270 = 10623
  TriggerConfig c = OneLine(100'000, 100);
  for (LineConfig& l : c.lines) l = {true, 100, 0, 0, proto::ExposureInput::kActiveHigh};
  EXPECT_EQ(CheckConfig(c).field, proto::Field::kRate);  // 100 Hz x 8 wired lines
  c.rate_mhz = 40'000;
  EXPECT_TRUE(CheckConfig(c).ok());
}

}  // namespace
}  // namespace rigcal::trigger_core
