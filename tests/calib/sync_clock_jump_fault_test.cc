// SPDX-License-Identifier: Apache-2.0
// Clock jumps of free-running slaves in the SyncBuffer (interpolation mode): a slave whose clock
// restarted (stamps restart near 0, or step by seconds) is followed once its new timeline is
// persistent and self-consistent, with the step as the offset prior, counted and warned about
// once; isolated glitches, bursts without a steady rate and old data replayed by every camera
// stay rejected; a slave that does not follow jumps (a given offset) stays rejected. The same for
// the master's clock: followed by stepping the slave's offset the other way, the slave matched on
// without a new search; isolated master glitches stay rejected.
#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "rigcal/base/logging.h"
#include "rigcal/calib/sync_buffer.h"

namespace rigcal {
namespace {

constexpr int64_t kStart = 10'000'000'000;
constexpr int64_t kPeriod = 50'000'000;  // 20 Hz
constexpr int64_t kPhase = 17'000'000;   // the slave captures 17 ms after the master
constexpr int64_t kOffset = 30'000'000;  // the slave's clock before the jump

CameraPose Entry(int camera, int64_t t_ns, int64_t true_ns) {
  CameraPose p;
  p.camera = camera;
  p.t_ns = t_ns;
  // A rotation about z at 0.5 rad/s: interpolation has something to interpolate.
  const double angle = 0.5 * static_cast<double>(true_ns - kStart) * 1e-9;
  p.pose.q = Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
  return p;
}

SyncOptions FreeRunning(bool follow) {
  SyncOptions o;
  o.num_cameras = 2;
  o.frame_period_ns = kPeriod;
  o.interpolate = true;
  o.ready_capacity = 8192;
  if (follow) o.follow_clock_jumps = {false, true};
  return o;
}

struct Outcome {
  std::vector<PushResult> slave;       // every slave push's result, in order
  uint64_t sets_with_slave_after = 0;  // sets after `jump_frame` that have the slave
};

// `frames` frames of master and slave in capture order; the slave's stamp of frame k (true
// instant t) is clock(k, t). The buffer's offset is kOffset from the start.
Outcome Feed(SyncBuffer* buffer, int frames, int jump_frame,
             const std::function<int64_t(int, int64_t)>& clock) {
  buffer->SetTimeOffset(1, kOffset);
  Outcome out;
  MatchedSet set;
  for (int k = 0; k < frames; ++k) {
    const int64_t t = kStart + k * kPeriod;
    buffer->Push(Entry(0, t, t));
    out.slave.push_back(buffer->Push(Entry(1, clock(k, t + kPhase), t + kPhase)));
    while (buffer->TryPop(&set)) {
      if (set.t_ns > kStart + jump_frame * kPeriod && set.poses[1]) ++out.sets_with_slave_after;
    }
  }
  return out;
}

void ExpectCountsAddUp(const SyncStats& s) {
  for (const SyncCameraStats& k : s.cameras) {
    EXPECT_EQ(k.pushed, k.used + k.Dropped() + k.fill) << s.BriefReport();
  }
}

int Rejected(const std::vector<PushResult>& results) {
  int n = 0;
  for (const PushResult r : results) n += r != PushResult::kAccepted;
  return n;
}

struct StepCase {
  const char* name;
  int64_t new_offset_ns;  // the slave's clock after frame 200
};

class SyncClockJump : public ::testing::TestWithParam<StepCase> {};

TEST_P(SyncClockJump, ARestartedSlaveClockIsFollowedWithTheStepAsPrior) {
  const StepCase& c = GetParam();
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(256);
  const auto log = ModuleLogger("calib");
  log->sinks().push_back(sink);
  SyncBuffer buffer(FreeRunning(true));
  const Outcome out = Feed(&buffer, 600, 200, [&](int k, int64_t t) {
    return t + (k < 200 ? kOffset : c.new_offset_ns);
  });
  log->sinks().pop_back();
  const ClockJump jump = buffer.ClockJumps(1);
  EXPECT_EQ(jump.count, 1u);
  // The prior: the step, within a frame (the master's newest stamp when a slave pose arrives
  // lags its instant by up to a frame).
  EXPECT_NEAR(static_cast<double>(jump.offset_ns), static_cast<double>(c.new_offset_ns),
              static_cast<double>(kPeriod));
  EXPECT_EQ(jump.step_ns, jump.offset_ns - kOffset);
  // 9 poses rejected, the 10th accepted as the first of the new timeline; none before.
  EXPECT_EQ(Rejected(out.slave), 9);
  for (int k = 0; k < 200; ++k) EXPECT_EQ(out.slave[k], PushResult::kAccepted) << k;
  EXPECT_EQ(out.slave[209], PushResult::kAccepted);
  // Matching goes on with the slave at the prior (its own offset estimator refines it).
  EXPECT_GE(out.sets_with_slave_after, 600u - 200u - 20u);
  buffer.Flush();
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[1].clock_jumps, 1u);
  EXPECT_NE(s.BriefReport().find("clock_jumps 1"), std::string::npos) << s.BriefReport();
  ExpectCountsAddUp(s);
  int warnings = 0;
  for (const auto& m : sink->last_raw()) {
    const std::string text(m.payload.data(), m.payload.size());
    warnings += m.level == spdlog::level::warn && text.find("clock restarted") != std::string::npos;
  }
  EXPECT_EQ(warnings, 1) << "one warning per jump";
}

INSTANTIATE_TEST_SUITE_P(Steps, SyncClockJump,
                         ::testing::Values(StepCase{"stamps restart near 0",
                                                    -kStart - 9'900'000'000},
                                           StepCase{"back 1.5 s", kOffset - 1'500'000'000},
                                           StepCase{"back 0.6 s", kOffset - 600'000'000},
                                           StepCase{"ahead 1.2 s", kOffset + 1'200'000'000},
                                           StepCase{"ahead 0.4 s", kOffset + 400'000'000},
                                           StepCase{"ahead 1 h", kOffset + 3'600'000'000'000}),
                         [](const ::testing::TestParamInfo<StepCase>& info) {
                           std::string name = info.param.name;
                           for (char& ch : name)
                             ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
                           return name;
                         });

TEST(SyncClockJumpRule, IsolatedGlitchesAndBurstsWithoutASteadyRateStayRejected) {
  SyncBuffer buffer(FreeRunning(true));
  const Outcome out = Feed(&buffer, 600, 0, [&](int k, int64_t t) {
    if (k % 10 == 5) return t + kOffset + 10'000'000'000;  // one in ten, 10 s ahead
    // A burst in the past, stepping by 6 frame intervals or back: no steady rate.
    if (k >= 300 && k < 340) return 1'000'000'000 + (k % 7) * 6 * kPeriod;
    return t + kOffset;
  });
  EXPECT_EQ(buffer.ClockJumps(1).count, 0u);
  EXPECT_EQ(Rejected(out.slave), 60 + 36);
  buffer.Flush();
  ExpectCountsAddUp(buffer.stats());
}

TEST(SyncClockJumpRule, OldDataReplayedByEveryCameraIsNotANewClock) {
  SyncBuffer buffer(FreeRunning(true));
  buffer.SetTimeOffset(1, kOffset);
  auto push_frames = [&](int from, int to) {
    std::vector<PushResult> slave;
    for (int k = from; k < to; ++k) {
      const int64_t t = kStart + k * kPeriod;
      buffer.Push(Entry(0, t, t));
      slave.push_back(buffer.Push(Entry(1, t + kPhase + kOffset, t + kPhase)));
    }
    return slave;
  };
  push_frames(0, 300);
  // Frames 200..299 again (a replayed stretch of the log): the slave's stamps run at a steady
  // rate 5 s back, but so do the master's, which does not advance.
  const std::vector<PushResult> replayed = push_frames(200, 300);
  EXPECT_EQ(Rejected(replayed), 100);
  EXPECT_EQ(buffer.ClockJumps(1).count, 0u);
  const std::vector<PushResult> after = push_frames(300, 400);
  EXPECT_EQ(Rejected(after), 0);
  buffer.Flush();
  ExpectCountsAddUp(buffer.stats());
}

TEST(SyncClockJumpRule, ASlaveThatDoesNotFollowJumpsStaysRejected) {
  SyncBuffer buffer(FreeRunning(false));
  const Outcome out =
      Feed(&buffer, 400, 200, [&](int k, int64_t t) { return t + (k < 200 ? kOffset : -kStart); });
  EXPECT_EQ(buffer.ClockJumps(1).count, 0u);
  EXPECT_EQ(Rejected(out.slave), 200);
  EXPECT_EQ(out.sets_with_slave_after, 0u);
}

// The master's stamp of frame k (true instant t) is master_clock(k, t), the slave's t + kPhase +
// kOffset (its clock runs on). Counts the sets after `jump_frame` with the slave, and whether
// their interpolated slave instant is the true one (kOffset from the master's true instant).
struct MasterOutcome {
  std::vector<PushResult> master;
  uint64_t sets_with_slave_after = 0;
  uint64_t sets_matched_right_after = 0;
};

MasterOutcome FeedMaster(SyncBuffer* buffer, int frames, int jump_frame,
                         const std::function<int64_t(int, int64_t)>& master_clock) {
  buffer->SetTimeOffset(1, kOffset);
  MasterOutcome out;
  MatchedSet set;
  int64_t step = 0;  // the master's clock step in effect for a set (its master_clock_step_ns)
  for (int k = 0; k < frames; ++k) {
    const int64_t t = kStart + k * kPeriod;
    out.master.push_back(buffer->Push(Entry(0, master_clock(k, t), t)));
    buffer->Push(Entry(1, t + kPhase + kOffset, t + kPhase));
    while (buffer->TryPop(&set)) {
      step = set.master_clock_step_ns;
      const int64_t true_t = set.t_ns - step;  // the master's clock at the start
      if (true_t <= kStart + jump_frame * kPeriod || !set.poses[1]) continue;
      ++out.sets_with_slave_after;
      // The slave's instant on its clock is the master's true instant + kOffset (to within
      // the error of the measured step, below a frame).
      const int64_t error = set.poses[1]->t_ns - (true_t + kOffset);
      out.sets_matched_right_after += std::abs(error) < kPeriod / 2;
    }
  }
  return out;
}

class SyncMasterClockJump : public ::testing::TestWithParam<StepCase> {};

SyncOptions FreeRunningWithMaster() {
  SyncOptions o = FreeRunning(true);
  o.follow_clock_jumps = {true, true};
  return o;
}

TEST_P(SyncMasterClockJump, ARestartedMasterClockIsFollowedByMovingTheSlavesOffsets) {
  const StepCase& c = GetParam();  // new_offset_ns: the master's clock step
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(256);
  const auto log = ModuleLogger("calib");
  log->sinks().push_back(sink);
  SyncBuffer buffer(FreeRunningWithMaster());
  const MasterOutcome out = FeedMaster(
      &buffer, 600, 200, [&](int k, int64_t t) { return t + (k < 200 ? 0 : c.new_offset_ns); });
  log->sinks().pop_back();
  const ClockJump jump = buffer.ClockJumps(0);
  EXPECT_EQ(jump.count, 1u);
  EXPECT_NEAR(static_cast<double>(jump.step_ns), static_cast<double>(c.new_offset_ns),
              static_cast<double>(kPeriod) / 4);
  EXPECT_EQ(jump.offset_ns, jump.step_ns);
  EXPECT_EQ(buffer.ClockJumps(1).count, 0u) << "the slave's clock did not restart";
  EXPECT_EQ(Rejected(out.master), 9);
  for (int k = 0; k < 200; ++k) EXPECT_EQ(out.master[k], PushResult::kAccepted) << k;
  EXPECT_EQ(out.master[209], PushResult::kAccepted);
  // The slave is matched on at once, at the offset moved by the step (no new search).
  EXPECT_GE(out.sets_with_slave_after, 600u - 200u - 20u);
  EXPECT_EQ(out.sets_matched_right_after, out.sets_with_slave_after);
  buffer.Flush();
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].clock_jumps, 1u);
  EXPECT_EQ(s.cameras[1].clock_jumps, 0u);
  ExpectCountsAddUp(s);
  int warnings = 0;
  for (const auto& m : sink->last_raw()) {
    const std::string text(m.payload.data(), m.payload.size());
    warnings += m.level == spdlog::level::warn &&
                text.find("master's clock (camera 0) restarted") != std::string::npos;
  }
  EXPECT_EQ(warnings, 1) << "one warning per jump";
}

INSTANTIATE_TEST_SUITE_P(Steps, SyncMasterClockJump,
                         ::testing::Values(StepCase{"stamps restart near 0", -kStart + 5'000'000},
                                           StepCase{"back 1.5 s", -1'500'000'000},
                                           StepCase{"ahead 1 h", 3'600'000'000'000}),
                         [](const ::testing::TestParamInfo<StepCase>& info) {
                           std::string name = info.param.name;
                           for (char& ch : name)
                             ch = std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
                           return name;
                         });

TEST(SyncMasterClockJumpRule, IsolatedMasterGlitchesStayRejected) {
  SyncBuffer buffer(FreeRunningWithMaster());
  const MasterOutcome out = FeedMaster(&buffer, 600, 0, [&](int k, int64_t t) {
    if (k % 10 == 5) return t + 10'000'000'000;            // one in ten, 10 s ahead
    if (k % 10 == 7 && k > 100) return t - 3'000'000'000;  // one in ten, 3 s back
    return t;
  });
  EXPECT_EQ(buffer.ClockJumps(0).count, 0u);
  EXPECT_EQ(Rejected(out.master), 60 + 50);
  EXPECT_EQ(out.sets_matched_right_after, out.sets_with_slave_after);
  buffer.Flush();
  ExpectCountsAddUp(buffer.stats());
}

TEST(SyncMasterClockJumpRule, OldDataReplayedByEveryCameraIsNotANewMasterClock) {
  SyncBuffer buffer(FreeRunningWithMaster());
  buffer.SetTimeOffset(1, kOffset);
  auto push_frames = [&](int from, int to) {
    std::vector<PushResult> master;
    for (int k = from; k < to; ++k) {
      const int64_t t = kStart + k * kPeriod;
      master.push_back(buffer.Push(Entry(0, t, t)));
      buffer.Push(Entry(1, t + kPhase + kOffset, t + kPhase));
    }
    return master;
  };
  push_frames(0, 300);
  const std::vector<PushResult> replayed = push_frames(200, 300);
  EXPECT_EQ(Rejected(replayed), 100);
  EXPECT_EQ(buffer.ClockJumps(0).count, 0u);
  EXPECT_EQ(Rejected(push_frames(300, 400)), 0);
}

TEST(SyncMasterClockJumpRule, AMasterThatDoesNotFollowJumpsStaysRejected) {
  SyncBuffer buffer(FreeRunning(true));
  const MasterOutcome out =
      FeedMaster(&buffer, 400, 200, [&](int k, int64_t t) { return k < 200 ? t : t - kStart; });
  EXPECT_EQ(buffer.ClockJumps(0).count, 0u);
  EXPECT_EQ(Rejected(out.master), 200);
  EXPECT_EQ(out.sets_with_slave_after, 0u);
}

TEST(SyncClockJumpRule, OptionsNameTheField) {
  SyncOptions o = FreeRunning(true);
  o.follow_clock_jumps = {false};
  EXPECT_EQ(o.Check().message(),
            "follow_clock_jumps: must be empty or have num_cameras (2) flags, got 1");
  o = FreeRunning(true);
  o.interpolate = false;
  EXPECT_EQ(o.Check().message(),
            "follow_clock_jumps: only with interpolate (cameras that run free)");
}

}  // namespace
}  // namespace rigcal
