// The trigger scheduler (firmware/core): tick times, exposure-centred rises, phase offsets,
// widths, reports (order, seq, never before the tick), stop/start, late and skipped ticks.
#include "rigcal/trigger_core/scheduler.h"

#include <gtest/gtest.h>

#include <vector>

namespace rigcal::trigger_core {
namespace {

struct Edge {
  uint64_t t_us;
  int line;
  bool high;
};

// Records every line change and report with the time of the Poll that produced it.
class Recorder : public SchedulerListener {
 public:
  void OnLines(uint8_t mask) override {
    for (int i = 0; i < proto::kMaxLines; ++i) {
      if (((mask ^ mask_) >> i) & 1u) edges.push_back({now, i, ((mask >> i) & 1u) != 0});
    }
    mask_ = mask;
  }
  void OnPulse(const proto::PulseReport& r) override {
    reports.push_back(r);
    report_times.push_back(now);
  }
  uint64_t now = 0;
  std::vector<Edge> edges;
  std::vector<proto::PulseReport> reports;
  std::vector<uint64_t> report_times;
  uint8_t mask_ = 0;
};

// Polls exactly at every event time (an ideal board) until `end_us`.
void RunUntil(Scheduler* s, Recorder* r, uint64_t end_us) {
  while (true) {
    const uint64_t next = s->NextEventUs();
    if (next > end_us) break;
    r->now = next;
    s->Poll(next, r);
  }
}

std::vector<Edge> EdgesOf(const Recorder& r, int line, bool high) {
  std::vector<Edge> out;
  for (const Edge& e : r.edges) {
    if (e.line == line && e.high == high) out.push_back(e);
  }
  return out;
}

TriggerConfig OneLine(uint32_t rate_mhz, uint32_t width_us) {
  TriggerConfig c;
  c.rate_mhz = rate_mhz;
  c.lines[0].enabled = true;
  c.lines[0].width_us = width_us;
  return c;
}

TEST(Scheduler, OneLineRisesAtEveryTickAndReportsIt) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(20'000, 100)));  // 20 Hz
  ASSERT_TRUE(s.Start(1'000));
  Recorder r;
  RunUntil(&s, &r, 1'000 + 1'000'000 - 1);  // one second
  const std::vector<Edge> rises = EdgesOf(r, 0, true);
  const std::vector<Edge> falls = EdgesOf(r, 0, false);
  ASSERT_EQ(rises.size(), 20u);
  ASSERT_EQ(falls.size(), 20u);
  ASSERT_EQ(r.reports.size(), 20u);
  for (size_t k = 0; k < rises.size(); ++k) {
    EXPECT_EQ(rises[k].t_us, 1'000 + 50'000 * k);
    EXPECT_EQ(falls[k].t_us, rises[k].t_us + 100);
    EXPECT_EQ(r.reports[k].seq, k);
    EXPECT_EQ(r.reports[k].mcu_time_us, rises[k].t_us);
    EXPECT_EQ(r.reports[k].line_mask, 0x01);
    EXPECT_EQ(r.report_times[k], rises[k].t_us);
  }
  EXPECT_EQ(s.late_edges(), 0u);
}

TEST(Scheduler, ExposureCentredRisesWithPhaseOffsets) {
  TriggerConfig c;
  c.rate_mhz = 10'000;                     // 100 ms
  c.lines[0] = {true, 200, 0, 10'000};     // rises 5 ms before the tick
  c.lines[3] = {true, 300, 2'000, 4'000};  // centre 2 ms after the tick: rises at the tick
  c.lines[5] = {true, 50, 7'000, 0};       // rises 7 ms after the tick
  Scheduler s;
  ASSERT_TRUE(s.Configure(c));
  ASSERT_TRUE(s.Start(1'000));
  Recorder r;
  RunUntil(&s, &r, 1'000'000);
  const uint64_t t0 = 1'000 + 5'000;  // the largest lead: the first rise is at the start time
  ASSERT_GE(r.reports.size(), 9u);
  for (size_t k = 0; k < 9; ++k) {
    const uint64_t tk = t0 + 100'000 * k;
    EXPECT_EQ(EdgesOf(r, 0, true)[k].t_us, tk - 5'000);
    EXPECT_EQ(EdgesOf(r, 0, false)[k].t_us, tk - 5'000 + 200);
    EXPECT_EQ(EdgesOf(r, 3, true)[k].t_us, tk);
    EXPECT_EQ(EdgesOf(r, 3, false)[k].t_us, tk + 300);
    EXPECT_EQ(EdgesOf(r, 5, true)[k].t_us, tk + 7'000);
    // The report carries T_k and leaves after every rise of its tick.
    EXPECT_EQ(r.reports[k].mcu_time_us, tk);
    EXPECT_EQ(r.reports[k].line_mask, (1u << 0) | (1u << 3) | (1u << 5));
    EXPECT_EQ(r.report_times[k], tk + 7'000);
  }
  EXPECT_TRUE(EdgesOf(r, 1, true).empty());
}

TEST(Scheduler, FractionalPeriodsDoNotAccumulateRoundingError) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(30'000, 100)));  // 30 Hz: 33333.3 µs
  ASSERT_TRUE(s.Start(0));
  Recorder r;
  RunUntil(&s, &r, 100'000'000);  // 100 s
  ASSERT_EQ(r.reports.size(), 3001u);
  EXPECT_EQ(r.reports[3000].mcu_time_us, 100'000'000u);  // exactly 3000 periods
  EXPECT_EQ(r.reports[1].mcu_time_us, 33'333u);
  EXPECT_EQ(r.reports[2].mcu_time_us, 66'666u);
  for (size_t k = 1; k < r.reports.size(); ++k) {
    const uint64_t d = r.reports[k].mcu_time_us - r.reports[k - 1].mcu_time_us;
    ASSERT_TRUE(d == 33'333u || d == 33'334u) << k;
  }
}

TEST(Scheduler, StopDropsTheLinesAndSequenceNumbersContinueAfterRestart) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(100'000, 5'000)));  // 100 Hz, 5 ms wide
  ASSERT_TRUE(s.Start(0));
  Recorder r;
  RunUntil(&s, &r, 32'000);  // ticks 0..3; line high since 30 ms
  ASSERT_EQ(r.reports.size(), 4u);
  ASSERT_TRUE(r.edges.back().high);
  EXPECT_FALSE(s.Start(32'000));  // already running
  s.Stop(&r);
  EXPECT_FALSE(r.edges.back().high);
  EXPECT_EQ(s.NextEventUs(), UINT64_MAX);
  r.now = 500'000;
  s.Poll(500'000, &r);
  EXPECT_EQ(r.reports.size(), 4u);
  EXPECT_EQ(s.next_seq(), 4u);
  ASSERT_TRUE(s.Start(1'000'000));
  RunUntil(&s, &r, 1'000'000 + 25'000);
  ASSERT_EQ(r.reports.size(), 7u);
  EXPECT_EQ(r.reports[4].seq, 4u);
  EXPECT_EQ(r.reports[4].mcu_time_us, 1'000'000u);
  EXPECT_EQ(r.reports[6].seq, 6u);
}

TEST(Scheduler, ConfigurationIsRefusedWhileRunningOrInvalid) {
  Scheduler s;
  TriggerConfig bad = OneLine(20'000, 50'000);  // width == period
  EXPECT_FALSE(s.Configure(bad));
  EXPECT_FALSE(s.Start(0));  // default config has no line enabled
  ASSERT_TRUE(s.Configure(OneLine(20'000, 100)));
  ASSERT_TRUE(s.Start(0));
  EXPECT_FALSE(s.Configure(OneLine(10'000, 100)));
  EXPECT_EQ(s.config().rate_mhz, 20'000u);
}

TEST(Scheduler, LatePollsAreCountedAndLongStallsSkipTicks) {
  Scheduler s;
  ASSERT_TRUE(s.Configure(OneLine(100'000, 100)));  // 10 ms period
  ASSERT_TRUE(s.Start(0));
  Recorder r;
  // 200 µs late for tick 0: the rise and the fall are late, the tick is still reported.
  r.now = 200;
  s.Poll(200, &r);
  EXPECT_EQ(r.reports.size(), 1u);
  EXPECT_EQ(s.late_edges(), 2u);
  // A stall of 10.5 periods: ticks 1..9 are skipped, tick 10 is raised late and reported.
  r.now = 105'000;
  s.Poll(105'000, &r);
  ASSERT_EQ(r.reports.size(), 2u);
  EXPECT_EQ(r.reports[1].seq, 10u);
  EXPECT_EQ(r.reports[1].mcu_time_us, 100'000u);
  EXPECT_EQ(s.skipped_ticks(), 9u);
  RunUntil(&s, &r, 125'000);
  ASSERT_EQ(r.reports.size(), 4u);
  EXPECT_EQ(r.reports[3].seq, 12u);
  EXPECT_EQ(r.reports[3].mcu_time_us, 120'000u);
}

TEST(TriggerConfig, RangeChecksNameTheField) {
  EXPECT_EQ(CheckRate(99).field, proto::Field::kRate);
  EXPECT_TRUE(CheckRate(100).ok());
  EXPECT_TRUE(CheckRate(400'000).ok());
  EXPECT_EQ(CheckRate(400'001).field, proto::Field::kRate);
  LineConfig line{true, 0, 0, 0};
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kWidth);
  line.width_us = 49'999;
  EXPECT_TRUE(CheckLine(line, 20'000).ok());
  line.width_us = 50'000;
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kWidth);
  line.width_us = 100;
  line.exposure_us = 1'000'001;
  EXPECT_EQ(CheckLine(line, 100).field, proto::Field::kExposure);
  line.exposure_us = 20'000;
  line.phase_offset_us = -39'999;  // 39999 + 20000 / 2 < 50000
  EXPECT_TRUE(CheckLine(line, 20'000).ok());
  line.phase_offset_us = -40'000;
  EXPECT_EQ(CheckLine(line, 20'000).field, proto::Field::kPhaseOffset);
  EXPECT_EQ(CheckHeartbeat(5).field, proto::Field::kHeartbeatPeriod);
  EXPECT_TRUE(CheckHeartbeat(0).ok());
  EXPECT_TRUE(CheckHeartbeat(10'000).ok());
  EXPECT_FALSE(CheckHeartbeat(10'001).ok());
}

}  // namespace
}  // namespace rigcal::trigger_core
