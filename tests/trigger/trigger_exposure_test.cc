// SPDX-License-Identifier: Apache-2.0
// Exposure feedback on the host (drivers TriggerMatcher): a line whose camera reports its
// measured exposure (ExposureReport, protocol version 2) gets the measured exposure centre instead
// of the scheduled one (T_k + phase offset); a camera marked exposure_feedback waits for the
// measurement and falls back to the schedule only once a later pulse has come without it; other
// lines keep the schedule.
#include <gtest/gtest.h>

#include <vector>

#include "rigcal/trigger/trigger_matcher.h"

namespace rigcal::trigger {
namespace {

namespace proto = ::rigcal::trigger_protocol;

constexpr int64_t kBootNs = 5'000'000'000;  // host time of MCU time 0
constexpr int64_t kDelayNs = 40'000;        // every message arrives 40 µs after it was sent

int64_t HostNs(uint64_t mcu_us) { return kBootNs + static_cast<int64_t>(mcu_us) * 1000; }

proto::Message Pulse(uint32_t seq, uint64_t t_us) {
  proto::Message m;
  m.type = proto::MessageType::kPulseReport;
  m.pulse = {0x03, seq, t_us};
  return m;
}
proto::Message Exposure(uint32_t seq, uint8_t line, uint64_t start_us, uint32_t duration_us) {
  proto::Message m;
  m.type = proto::MessageType::kExposureReport;
  m.exposure = {seq, line, start_us, duration_us};
  return m;
}

// 100 Hz on lines 0 and 1 with T_k = 10 ms * (k + 1); line 0's camera reports exposures that
// start 2.3 ms before T_k (its trigger) + 41 µs of latency and last 4.4 ms instead of 4 ms.
class ExposureFeed {
 public:
  ExposureFeed() {
    TriggerMatcherOptions o;
    o.clock.min_samples = 2;
    matcher = std::make_unique<TriggerMatcher>(o);
  }
  uint64_t TickUs(uint32_t k) const { return 10'000ull * (k + 1); }
  uint64_t MeasuredCentreUs(uint32_t k) const { return TickUs(k) - 2'000 + 41 + 2'200; }
  void SendPulse(uint32_t k) {
    matcher->OnMessage(Pulse(k, TickUs(k)), HostNs(TickUs(k)) + kDelayNs);
  }
  void SendExposure(uint32_t k) {
    const uint64_t start = TickUs(k) - 2'000 + 41;
    matcher->OnMessage(Exposure(k, 0, start, 4'400), HostNs(start + 4'400) + kDelayNs);
  }
  std::unique_ptr<TriggerMatcher> matcher;
};

TEST(TriggerExposure, AMeasuredExposureCentreReplacesTheScheduledOne) {
  ExposureFeed f;
  for (uint32_t k = 0; k < 50; ++k) {
    f.SendPulse(k);
    f.SendExposure(k);
  }
  // The clock map is the lower envelope: every sample 40 µs late maps MCU time 40 µs late.
  const CameraTriggerSpec wired{0, 0, 0, true};
  const CameraTriggerSpec plain{1, 0, 0, false};
  for (uint32_t k = 10; k < 50; ++k) {
    TriggerMatch m;
    ASSERT_EQ(f.matcher->Match(wired, HostNs(f.MeasuredCentreUs(k)) + 300'000, &m),
              MatchOutcome::kMatched);
    EXPECT_EQ(m.seq, k);
    EXPECT_TRUE(m.measured);
    EXPECT_NEAR(m.centre_ns, HostNs(f.MeasuredCentreUs(k)) + kDelayNs, 1'000) << k;
    TriggerMatch p;
    ASSERT_EQ(f.matcher->Match(plain, HostNs(f.TickUs(k)), &p), MatchOutcome::kMatched);
    EXPECT_FALSE(p.measured);
    EXPECT_NEAR(p.centre_ns, HostNs(f.TickUs(k)) + kDelayNs, 1'000);
  }
  // The measured centre is 241 µs after the scheduled one.
  EXPECT_EQ(f.MeasuredCentreUs(3) - f.TickUs(3), 241u);
  const TriggerMatcherStats s = f.matcher->stats();
  EXPECT_EQ(s.exposures, 50);
  EXPECT_EQ(s.exposures_orphaned, 0);
  EXPECT_EQ(s.measured_matches, 40);
}

TEST(TriggerExposure, AWiredCameraWaitsForItsMeasurementThenFallsBackToTheSchedule) {
  ExposureFeed f;
  for (uint32_t k = 0; k < 10; ++k) {
    f.SendPulse(k);
    f.SendExposure(k);
  }
  const CameraTriggerSpec wired{0, 0, 0, true};
  f.SendPulse(10);  // its exposure report is still on its way
  TriggerMatch m;
  EXPECT_EQ(f.matcher->Match(wired, HostNs(f.TickUs(10)), &m), MatchOutcome::kNotYet);
  f.SendExposure(10);
  ASSERT_EQ(f.matcher->Match(wired, HostNs(f.TickUs(10)), &m), MatchOutcome::kMatched);
  EXPECT_TRUE(m.measured);
  // Tick 11's report is lost (the capture missed an edge): once tick 12 is in, 11 takes the
  // scheduled centre and is counted.
  f.SendPulse(11);
  f.SendPulse(12);
  ASSERT_EQ(f.matcher->Match(wired, HostNs(f.TickUs(11)), &m), MatchOutcome::kMatched);
  EXPECT_EQ(m.seq, 11);
  EXPECT_FALSE(m.measured);
  EXPECT_NEAR(m.centre_ns, HostNs(f.TickUs(11)) + kDelayNs, 1'000);
  EXPECT_EQ(f.matcher->stats().exposure_missing, 1);
  // A report for a pulse the matcher never saw is counted, not used.
  f.matcher->OnMessage(Exposure(500, 0, 5'000'000, 100), HostNs(5'000'100));
  EXPECT_EQ(f.matcher->stats().exposures_orphaned, 1);
}

}  // namespace
}  // namespace rigcal::trigger
