// SPDX-License-Identifier: Apache-2.0
// The host trigger link end to end on a simulated link: the real firmware core on an MCU clock
// that drifts 50 ppm, frames delayed by a USB-like one-sided jitter of 0-2 ms, bytes corrupted,
// and an MCU reboot half-way. Prints the RMS error of the mapped pulse times (µs), the drift
// estimate and the time to re-sync after the reboot; asserts bounds derived from the injected
// jitter. Also: frames of triggered cameras get their pulse's sequence number.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "rigcal/sim/simulated_trigger.h"
#include "rigcal/trigger/trigger_clock_map.h"
#include "rigcal/trigger/trigger_matcher.h"
#include "rigcal/trigger/trigger_receiver.h"

namespace rigcal::trigger {
namespace {

using trigger_protocol::MessageType;

constexpr int64_t kSecond = 1'000'000'000;
constexpr int64_t kJitterNs = 2'000'000;  // uniform 0..2 ms

// Two cameras: line 0 with a 4 ms exposure, line 1 `offset_us` after it. A report leaves when
// every line has risen, so with a positive offset its clock sample carries that much extra
// delay (harmless, but only heartbeats are then close to the envelope).
TriggerSettings TwoCameras(int64_t offset_us) {
  TriggerSettings s;
  s.rate_hz = 20.0;
  s.lines = {{0, 1000, 0, 4000}, {1, 1000, offset_us, 0}};
  s.heartbeat_ms = 100;
  return s;
}

struct PulseError {
  int64_t rx_ns;
  int boot;
  double error_us;  // mapped - true, when the pulse was received
};

double Rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}

TEST(TriggerLinkFault, MapsPulseTimesThroughJitterDriftCorruptionAndAReboot) {
  sim::SimulatedTriggerOptions generator;
  generator.drift_ppm = 50.0;
  generator.delay_jitter_ns = kJitterNs;
  generator.corrupt_probability = 2e-4;  // per byte: about one frame in 250
  const int64_t t_start = generator.start_host_ns;
  const int64_t t_reset = t_start + 60 * kSecond;
  const int64_t t_end = t_start + 120 * kSecond;
  generator.reset_host_ns = {t_reset};
  generator.seed = 11;
  auto stream = std::make_unique<sim::SimulatedTriggerStream>(generator);
  sim::SimulatedTriggerStream* truth = stream.get();
  TriggerMatcher matcher;
  TriggerSession session(std::move(stream), TwoCameras(0), &matcher);
  std::vector<PulseError> errors;
  std::vector<int64_t> seqs;
  session.set_observer([&](const TriggerEvent& e) {
    if (e.message.type != MessageType::kPulseReport) return;
    const uint64_t mcu = e.message.pulse.mcu_time_us;
    // The boot the pulse was sent in: its true time is before its arrival.
    int boot = truth->boot();
    while (boot > 0 && truth->TrueHostNs(boot, mcu) > e.rx_ns) --boot;
    const std::optional<int64_t> mapped = matcher.MapMcuTime(mcu);
    if (mapped) {
      errors.push_back({e.rx_ns, boot, (*mapped - truth->TrueHostNs(boot, mcu)) * 1e-3});
    }
  });
  ASSERT_TRUE(session.Start().ok());
  while (truth->NowNs() < t_end) ASSERT_TRUE(session.Pump(50).ok());

  const TriggerMatcherStats stats = matcher.stats();
  // Steady state: from 10 s after each (re)boot on.
  std::vector<double> steady;
  double max_steady = 0.0;
  for (const PulseError& p : errors) {
    const int64_t boot_t = p.boot == 0 ? t_start : t_reset;
    if (p.rx_ns - boot_t >= 10 * kSecond) {
      steady.push_back(p.error_us);
      max_steady = std::max(max_steady, std::abs(p.error_us));
    }
  }
  // Re-sync: after the reboot, the time until every later error stays below 100 / 50 µs.
  auto resync_s = [&](double bound_us) {
    int64_t last_bad = t_reset;
    for (const PulseError& p : errors) {
      if (p.rx_ns > t_reset && std::abs(p.error_us) > bound_us) last_bad = p.rx_ns;
    }
    return static_cast<double>(last_bad - t_reset) * 1e-9;
  };
  std::printf(
      "trigger clock mapping (50 ppm drift, 0-2 ms one-sided jitter, %lld corrupted bytes, one "
      "reboot): RMS error %.1f us, max %.1f us over %zu pulses in steady state; drift estimate "
      "%.2f ppm; re-sync after the reboot: < 100 us after %.2f s, < 50 us after %.2f s; "
      "%lld MCU resets seen, %d reconfigurations, %lld seq gaps, %u frames dropped by "
      "CRC/framing\n",
      static_cast<long long>(truth->corrupted_bytes()), Rms(steady), max_steady, steady.size(),
      stats.drift_ppm, resync_s(100.0), resync_s(50.0), static_cast<long long>(stats.mcu_resets),
      session.reconfigurations(), static_cast<long long>(stats.seq_gaps),
      session.link().stats().Errors());

  // Bounds from the injected noise. The map's error is the gap of the lower envelope above the
  // true line: with delays uniform on [0, J], the smallest of m samples exceeds 0 by J / (m + 1)
  // on average, and a 20 s window holds m ~ 600 samples; the fitted line rests on two such
  // minima, so its error is a few J / m ~ 10 us. Bounds at J / 40 = 50 us (RMS) and J / 10 (max)
  // leave room for extrapolation to the newest sample and still fail a map that follows the
  // mean delay (J / 2 = 1 ms) or ignores the drift (50 ppm x 10 s = 500 us).
  ASSERT_GT(steady.size(), 1500u);
  EXPECT_LT(Rms(steady), kJitterNs / 40 * 1e-3);
  EXPECT_LT(max_steady, kJitterNs / 10 * 1e-3);
  // Drift: 50 ppm, fitted over a window of ~60 s of MCU time: error ~ 2 J / 60 s ~ 0.07 ppm.
  EXPECT_NEAR(stats.drift_ppm, 50.0, 1.0);
  EXPECT_EQ(stats.mcu_resets, 1);
  EXPECT_EQ(session.reconfigurations(), 1);
  EXPECT_GT(session.link().stats().Errors(), 0u) << "no corruption was injected";
  // Re-sync needs the smallest of a few dozen delays: J / 100 us within about 2 s at 30 samples/s.
  EXPECT_LT(resync_s(100.0), 3.0);
}

TEST(TriggerLinkFault, TriggeredFramesGetTheirPulse) {
  // Cameras on lines 0 (exposure 4 ms, stamped at the end of exposure by its driver) and 1
  // (phase offset 2 ms, stamped at the exposure centre), each stamp with ±0.3 ms host noise.
  sim::SimulatedTriggerOptions generator;
  generator.drift_ppm = -30.0;
  generator.delay_jitter_ns = kJitterNs;
  auto stream = std::make_unique<sim::SimulatedTriggerStream>(generator);
  sim::SimulatedTriggerStream* truth = stream.get();
  TriggerMatcher matcher;
  TriggerSession session(std::move(stream), TwoCameras(2000), &matcher);
  struct Tick {
    int64_t seq;
    int64_t true_ns;
  };
  std::vector<Tick> ticks;
  session.set_observer([&](const TriggerEvent& e) {
    if (e.message.type == MessageType::kPulseReport) {
      ticks.push_back({e.message.pulse.seq, truth->TrueHostNs(0, e.message.pulse.mcu_time_us)});
    }
  });
  ASSERT_TRUE(session.Start().ok());
  while (truth->NowNs() < generator.start_host_ns + 20 * kSecond) {
    ASSERT_TRUE(session.Pump(50).ok());
  }
  ASSERT_GT(ticks.size(), 300u);
  const CameraTriggerSpec cam0{0, 0, 2'000'000};
  const CameraTriggerSpec cam1{1, 2'000'000, 0};
  std::mt19937 rng(5);
  std::uniform_int_distribution<int64_t> noise(-300'000, 300'000);
  int matched = 0;
  for (const Tick& t : ticks) {
    if (t.true_ns < generator.start_host_ns + 2 * kSecond) continue;  // let the map settle
    for (const CameraTriggerSpec* cam : {&cam0, &cam1}) {
      const int64_t stamp = t.true_ns + cam->phase_offset_ns + cam->stamp_offset_ns + noise(rng);
      TriggerMatch m;
      ASSERT_EQ(matcher.Match(*cam, stamp, &m), MatchOutcome::kMatched) << "seq " << t.seq;
      EXPECT_EQ(m.seq, t.seq);
      EXPECT_NEAR(static_cast<double>(m.centre_ns),
                  static_cast<double>(t.true_ns + cam->phase_offset_ns), 100'000.0);
      ++matched;
    }
  }
  EXPECT_GT(matched, 600);
  // A stamp between two pulses (25 ms from both, tolerance 5 ms): no pulse. A stamp after the
  // newest report: not yet.
  TriggerMatch m;
  EXPECT_EQ(matcher.Match(cam1, ticks[100].true_ns + 2'000'000 + 25'000'000, &m),
            MatchOutcome::kNoPulse);
  EXPECT_EQ(matcher.Match(cam1, ticks.back().true_ns + 2'000'000 + 50'000'000, &m),
            MatchOutcome::kNotYet);
}

TEST(TriggerClockMap, RecoversAnExactLineAndRestartsWhenTheClockGoesBack) {
  TriggerClockMapOptions o;
  o.min_span_us = 1'000'000;
  TriggerClockMap map(o);
  EXPECT_FALSE(map.ToHostNs(0).has_value());
  // host = 5 s + 1.0001 * mcu (MCU slow by ~100 ppm), delays 0 or +3 ms alternately.
  for (int i = 0; i < 100; ++i) {
    const uint64_t mcu = 100'000ull * i;
    const int64_t host =
        5 * kSecond + static_cast<int64_t>(std::llround(1000.1 * mcu)) + (i % 2 ? 3'000'000 : 0);
    ASSERT_NE(map.Add(mcu, host), TriggerClockMap::SampleResult::kRejectedEarly);
  }
  ASSERT_TRUE(map.drift_fitted());
  EXPECT_NEAR(static_cast<double>(*map.ToHostNs(20'000'000)), 5e9 + 1000.1 * 20'000'000, 2.0);
  EXPECT_NEAR(map.drift_ppm(), -100.0, 0.01);
  // An early sample (2 ms below the line) is rejected; the map is unchanged.
  EXPECT_EQ(map.Add(10'000'000, 5 * kSecond + 10'001'000'000 - 2'000'000),
            TriggerClockMap::SampleResult::kRejectedEarly);
  EXPECT_EQ(map.rejected(), 1);
  // MCU time going back: a reboot.
  EXPECT_EQ(map.Add(1'000, 100 * kSecond), TriggerClockMap::SampleResult::kRestarted);
  EXPECT_EQ(map.resets(), 1);
  EXPECT_EQ(map.samples(), 1u);
  EXPECT_FALSE(map.synced());
}

}  // namespace
}  // namespace rigcal::trigger
