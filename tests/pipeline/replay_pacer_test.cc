// SPDX-License-Identifier: Apache-2.0
// ReplayPacer: the log time of a paced replay follows the log at its normal rate, not glitched
// stamps (INT64_MAX, a run of one camera on a timeline of its own), follows a restart of the
// log's clock once events of two cameras (or 40 of one alone) confirm it, and never makes one
// wait longer than its cap / speed.
#include "rigcal/pipeline/replay_pacer.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <limits>

namespace rigcal::pipeline {
namespace {

using Step = ReplayPacer::Step;
constexpr int64_t kPeriod = 50'000'000;  // 20 Hz
const ReplayPacer::Clock::time_point kWall{};

// Two cameras at 20 Hz from stamp t0 for `frames` frames.
void Feed(ReplayPacer* pacer, int64_t t0, int frames) {
  for (int k = 0; k < frames; ++k) {
    for (int c = 0; c < 2; ++c) {
      EXPECT_EQ(pacer->Observe(c, t0 + k * kPeriod, kWall),
                k == 0 && c == 0 && t0 == 0 ? Step::kFirst : Step::kOnTime);
    }
  }
}

TEST(ReplayPacer, GlitchedStampsMoveNoClock) {
  ReplayPacer pacer;
  Feed(&pacer, 0, 100);
  EXPECT_EQ(pacer.CapNs(), 1'000'000'000);  // max(1 s, 20 x 50 ms)
  EXPECT_EQ(pacer.Observe(0, std::numeric_limits<int64_t>::max(), kWall), Step::kGlitch);
  // Ten of one camera at its rate on a timeline of its own, back to back.
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(pacer.Observe(0, 4'000'000'000'000'000'000 + i * kPeriod, kWall), Step::kGlitch);
  }
  EXPECT_EQ(pacer.now_ns(), 99 * kPeriod);
  EXPECT_EQ(pacer.glitches(), 11u);
  Feed(&pacer, 100 * kPeriod, 100);  // the log goes on: every event on time
  EXPECT_EQ(pacer.now_ns(), 199 * kPeriod);
  EXPECT_EQ(pacer.new_timelines(), 0u);
  // Paced from the origin at 1x: the log's 199 frame periods, no more.
  EXPECT_EQ(pacer.Due(1.0) - kWall, std::chrono::nanoseconds(199 * kPeriod));
}

TEST(ReplayPacer, ARestartOfTheLogsClockIsFollowedOnceConfirmed) {
  ReplayPacer pacer;
  Feed(&pacer, 0, 100);
  // Both cameras 1 h later: four events of the two confirm the new timeline.
  const int64_t later = 3'600'000'000'000;
  std::vector<Step> steps;
  for (int k = 0; k < 3; ++k) {
    for (int c = 0; c < 2; ++c) steps.push_back(pacer.Observe(c, later + k * kPeriod, kWall));
  }
  EXPECT_EQ(steps, (std::vector<Step>{Step::kGlitch, Step::kGlitch, Step::kGlitch, Step::kNewTime,
                                      Step::kOnTime, Step::kOnTime}));
  EXPECT_EQ(pacer.now_ns(), later + 2 * kPeriod);
  // The gap is not waited for: due one frame after the wall time the new timeline was taken.
  const auto taken = kWall + std::chrono::seconds(1);
  ReplayPacer again;
  Feed(&again, 0, 10);
  for (int i = 0; i < ReplayPacer::kLoneEvents; ++i) {
    const Step step = again.Observe(0, later + i * kPeriod, taken);
    EXPECT_EQ(step, i + 1 < ReplayPacer::kLoneEvents ? Step::kGlitch : Step::kNewTime) << i;
  }
  EXPECT_EQ(again.Observe(0, later + ReplayPacer::kLoneEvents * kPeriod, taken), Step::kOnTime);
  EXPECT_EQ(again.Due(1.0) - taken, std::chrono::nanoseconds(kPeriod));
}

TEST(ReplayPacer, NoWaitIsLongerThanTheCap) {
  ReplayPacer pacer;
  Feed(&pacer, 0, 10);
  const auto before = pacer.Due(0.5);
  // A pause of 0.9 s in the log (within the 1 s cap) is waited for, at half speed 1.8 s.
  EXPECT_EQ(pacer.Observe(0, 9 * kPeriod + 900'000'000, kWall), Step::kOnTime);
  EXPECT_EQ(pacer.Due(0.5) - before, std::chrono::nanoseconds(1'800'000'000));
  // Events behind the clock need no wait and move nothing: within the cap, and a camera's
  // events seconds late in the file (record --fast) too, which are no glitch.
  EXPECT_EQ(pacer.Observe(1, 9 * kPeriod, kWall), Step::kOnTime);
  EXPECT_EQ(pacer.now_ns(), 9 * kPeriod + 900'000'000);
  for (int k = 0; k < 50; ++k) {
    const int64_t t = 9 * kPeriod + 900'000'000 + k * kPeriod;
    EXPECT_EQ(pacer.Observe(0, t, kWall), Step::kOnTime) << k;
    EXPECT_EQ(pacer.Observe(1, t - 3'000'000'000, kWall), Step::kBehind) << k;
  }
  EXPECT_EQ(pacer.glitches(), 0u);
  EXPECT_EQ(pacer.new_timelines(), 0u);
}

}  // namespace
}  // namespace rigcal::pipeline
