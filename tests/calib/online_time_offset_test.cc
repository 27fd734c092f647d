// SPDX-License-Identifier: Apache-2.0
// Cameras that run free, online: the SyncBuffer's interpolation at the master's instants, the
// ClockOffsetTracker (initial correlation, Kalman refinement, drift, jumps) and the
// OnlineCalibrator with the offset as a state, against simulated rigs with known clocks.
#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>

#include <cmath>
#include <functional>
#include <memory>

#include "../calib/free_running_rig.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/clock_offset_tracker.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/online_calibrator.h"
#include "rigcal/calib/sync_buffer.h"

namespace rigcal {
namespace {

using free_running::CameraClock;
using free_running::FreeRunningRig;
using free_running::InCaptureOrder;
using free_running::MakeFreeRunningRig;

constexpr double kSigmas = 4.0;  // an estimate within kSigmas σ of the truth passes
constexpr int64_t kFrameNs = 50'000'000;

std::vector<Similarity> TwoSlaves() {
  const std::vector<Similarity> demo = DemoRig();
  return {demo[0], demo[1]};
}

// A rig whose stamps are the true instants (offsets are applied by InCaptureOrder).
FreeRunningRig Rig(std::vector<CameraClock> clocks, double duration_s, DriveOptions options) {
  for (CameraClock& c : clocks) c.offset_s = 0.0;
  return MakeFreeRunningRig({}, clocks, TwoSlaves(), duration_s, options);
}

std::function<int64_t(int, int64_t)> Constant(std::vector<double> offsets_s) {
  return [offsets_s](int slave, int64_t) { return std::llround(offsets_s[slave] * 1e9); };
}

TEST(SyncInterpolation, PhaseShiftedSlaveIsInterpolatedAtMasterInstantsWithBoundedLatency) {
  DriveOptions noiseless;
  noiseless.rotation_noise_deg = 0.0;
  noiseless.position_noise = 0.0;
  const FreeRunningRig rig = Rig({{20.0, 0.017}, {20.0, 0.031}}, 10.0, noiseless);
  const std::vector<double> offsets = {0.040, -0.100};
  SyncOptions options;
  options.num_cameras = 3;
  options.interpolate = true;
  options.max_wait_ns = 10 * kFrameNs;  // never reached: every set is final before
  SyncBuffer sync(options);
  for (int j = 1; j < 3; ++j) sync.SetTimeOffset(j, std::llround(offsets[j - 1] * 1e9));
  std::vector<MatchedSet> sets;
  MatchedSet set;
  for (const CameraPose& p : InCaptureOrder(rig, Constant(offsets))) {
    ASSERT_EQ(sync.Push(p), PushResult::kAccepted);
    // The pose was taken at its true instant: a set may wait for two more frames of each slave
    // (the cubic's last pose) after the master's instant, no more.
    const int64_t now = p.camera == 0 ? p.t_ns : p.t_ns - std::llround(offsets[p.camera - 1] * 1e9);
    while (sync.TryPop(&set)) {
      EXPECT_LE(now - set.t_ns, 2 * kFrameNs + kFrameNs / 2) << "set " << set.t_ns;
      sets.push_back(set);
    }
  }
  // Every master instant bracketed by both slaves gives a set (the first and last few do not).
  ASSERT_GE(sets.size(), rig.master.size() - 6);
  // Rotation angles of consecutive interpolated slave poses equal the master's (the rig is
  // rigid). Linear interpolation errs by up to a·dt²/8 (a ≈ 15 rad/s² here: 4.7e-3 rad); the
  // cubic's error is O(dt⁴), below 1e-4 rad. (The first two sets of a slave have no pose
  // before the one preceding the instant: linear.)
  for (size_t k = 3; k < sets.size(); ++k) {
    const double master_angle =
        RotationAngle(sets[k - 1].poses[0]->pose.q.conjugate() * sets[k].poses[0]->pose.q);
    for (int j = 1; j < 3; ++j) {
      ASSERT_TRUE(sets[k].poses[j]);
      EXPECT_EQ(sets[k].poses[j]->t_ns, sets[k].t_ns + std::llround(offsets[j - 1] * 1e9));
      const double slave_angle =
          RotationAngle(sets[k - 1].poses[j]->pose.q.conjugate() * sets[k].poses[j]->pose.q);
      EXPECT_NEAR(slave_angle, master_angle, 1e-4) << "set " << k << " slave " << j;
    }
  }
  sync.Flush();
  const SyncStats stats = sync.stats();
  for (const SyncCameraStats& c : stats.cameras) {
    EXPECT_EQ(c.pushed, c.used + c.Dropped() + c.fill) << stats.BriefReport();
  }
  EXPECT_GT(stats.cameras[1].used, 0u);
}

TEST(SyncInterpolation, SynchronisedStampsAreMatchedExactlyAsInStampMode) {
  DriveOptions options;
  const FreeRunningRig rig = Rig({{}, {}}, 5.0, options);
  auto run = [&](bool interpolate) {
    SyncOptions o;
    o.num_cameras = 3;
    o.interpolate = interpolate;
    SyncBuffer sync(o);
    std::vector<MatchedSet> sets;
    MatchedSet set;
    for (const CameraPose& p : InCaptureOrder(rig, Constant({0.0, 0.0}))) {
      sync.Push(p);
      while (sync.TryPop(&set)) sets.push_back(set);
    }
    sync.Flush();
    while (sync.TryPop(&set)) sets.push_back(set);
    return sets;
  };
  const std::vector<MatchedSet> by_stamp = run(false);
  const std::vector<MatchedSet> interpolated = run(true);
  ASSERT_EQ(by_stamp.size(), rig.master.size());
  ASSERT_EQ(interpolated.size(), by_stamp.size());
  for (size_t k = 0; k < by_stamp.size(); ++k) {
    for (int j = 0; j < 3; ++j) {
      ASSERT_TRUE(interpolated[k].poses[j]);
      EXPECT_EQ(interpolated[k].poses[j]->t_ns, by_stamp[k].poses[j]->t_ns);
      EXPECT_EQ(interpolated[k].poses[j]->pose.q.coeffs(), by_stamp[k].poses[j]->pose.q.coeffs());
      EXPECT_EQ(interpolated[k].poses[j]->pose.C, by_stamp[k].poses[j]->pose.C);
    }
  }
}

// Feeds the tracker every pose in capture order; `check` is called after each master pose.
void Track(ClockOffsetTracker* tracker, const FreeRunningRig& rig,
           const std::function<int64_t(int, int64_t)>& offset_ns) {
  for (const CameraPose& p : InCaptureOrder(rig, offset_ns)) tracker->Add(p);
}

struct TrackerCase {
  std::vector<CameraClock> clocks;  // rate and phase (the offset is in `offsets_s`)
  std::vector<double> offsets_s;
};

class ClockOffsetTrackerTest : public ::testing::TestWithParam<TrackerCase> {};

TEST_P(ClockOffsetTrackerTest, OffsetWithinSigmaOfTheTruth) {
  DriveOptions options;
  options.seed = 3;
  const TrackerCase& c = GetParam();
  const FreeRunningRig rig = Rig(c.clocks, 30.0, options);
  ClockOffsetOptions o;
  o.enabled = true;
  ClockOffsetTracker tracker({"master", "cam1", "cam2"}, o);
  Track(&tracker, rig, Constant(c.offsets_s));
  for (int i = 0; i < 2; ++i) {
    const SlaveClockOffset s = tracker.SlaveOffset(i);
    SCOPED_TRACE("slave " + std::to_string(i) + " true offset " + std::to_string(c.offsets_s[i]));
    ASSERT_TRUE(s.known && s.estimated);
    ASSERT_TRUE(std::isfinite(s.std_s));
    EXPECT_GT(s.std_s, 0.0);
    EXPECT_LT(s.std_s, 0.002);
    EXPECT_LE(std::abs(s.offset_s - c.offsets_s[i]), kSigmas * s.std_s) << s.offset_s;
    EXPECT_GT(s.measurements, 5);
    EXPECT_EQ(s.jumps, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Clocks, ClockOffsetTrackerTest,
                         ::testing::Values(TrackerCase{{{20.0, 0.017}, {30.0, 0.005}},
                                                       {0.100, -0.100}},
                                           TrackerCase{{{20.0, 0.031}, {20.0, 0.0}}, {-0.063, 0.0}},
                                           TrackerCase{{{}, {}}, {0.0, 0.0}}));

TEST(ClockOffsetTracker, FollowsClockDrift) {
  DriveOptions options;
  options.seed = 4;
  const FreeRunningRig rig = Rig({{20.0, 0.013}, {20.0, 0.029}}, 120.0, options);
  const double drift = 50e-6;  // 50 ppm: 6 ms over the run
  auto truth = [&](int slave, int64_t t_ns) {
    const double t = static_cast<double>(t_ns - rig.master.t_ns.front()) * 1e-9;
    return (slave == 0 ? 0.020 : -0.045) + (slave == 0 ? drift : -drift) * t;
  };
  ClockOffsetOptions o;
  o.enabled = true;
  ClockOffsetTracker tracker({"master", "cam1", "cam2"}, o);
  Track(&tracker, rig, [&](int slave, int64_t t) { return std::llround(truth(slave, t) * 1e9); });
  for (int i = 0; i < 2; ++i) {
    const SlaveClockOffset s = tracker.SlaveOffset(i);
    const double expected = truth(i, rig.master.t_ns.back());
    SCOPED_TRACE("slave " + std::to_string(i));
    ASSERT_TRUE(s.known);
    EXPECT_LE(std::abs(s.offset_s - expected), kSigmas * s.std_s)
        << s.offset_s << " vs " << expected;
    EXPECT_LE(std::abs(s.drift_ppm - (i == 0 ? 50.0 : -50.0)), kSigmas * s.drift_std_ppm)
        << s.drift_ppm << " ± " << s.drift_std_ppm;
    EXPECT_EQ(s.jumps, 0);
  }
}

TEST(ClockOffsetTracker, JumpIsDetectedWarnedAndReestimated) {
  DriveOptions options;
  options.seed = 6;
  const FreeRunningRig rig = Rig({{20.0, 0.011}, {20.0, 0.023}}, 60.0, options);
  const int64_t jump_at = rig.master.t_ns.front() + 30'000'000'000;
  auto offset = [&](int slave, int64_t t) -> int64_t {
    if (slave == 1) return 10'000'000;
    return t < jump_at ? 30'000'000 : -45'000'000;  // cam1 restarted at 30 s
  };
  auto sink = std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(128);
  const auto log = ModuleLogger("calib");
  log->sinks().push_back(sink);
  ClockOffsetOptions o;
  o.enabled = true;
  ClockOffsetTracker tracker({"master", "cam1", "cam2"}, o);
  Track(&tracker, rig, offset);
  log->sinks().pop_back();
  const SlaveClockOffset jumped = tracker.SlaveOffset(0);
  EXPECT_EQ(jumped.jumps, 1);
  ASSERT_TRUE(jumped.known);
  EXPECT_LE(std::abs(jumped.offset_s + 0.045), kSigmas * jumped.std_s) << jumped.offset_s;
  EXPECT_GT(jumped.usable_from_ns, jump_at);
  const SlaveClockOffset steady = tracker.SlaveOffset(1);
  EXPECT_EQ(steady.jumps, 0);
  EXPECT_LE(std::abs(steady.offset_s - 0.010), kSigmas * steady.std_s);
  bool warned = false;
  for (const auto& m : sink->last_raw()) {
    warned = warned || (m.level == spdlog::level::warn &&
                        std::string(m.payload.data(), m.payload.size()).find("'cam1' jumped") !=
                            std::string::npos);
  }
  EXPECT_TRUE(warned) << "no warning about the jump";
}

TEST(ClockOffsetTracker, GivenOffsetsAreHeld) {
  ClockOffsetOptions o;
  o.enabled = true;
  o.given_s = {0.025, std::nullopt};
  ClockOffsetTracker tracker({"master", "cam1", "cam2"}, o);
  EXPECT_TRUE(tracker.SlaveOffset(0).known);
  EXPECT_FALSE(tracker.SlaveOffset(0).estimated);
  EXPECT_EQ(tracker.SlaveOffset(0).offset_s, 0.025);
  EXPECT_TRUE(std::isnan(tracker.SlaveOffset(0).std_s));
  EXPECT_EQ(tracker.MatchingOffsetNs(0), 25'000'000);
  EXPECT_FALSE(tracker.SlaveOffset(1).known);
  o.given_s = {0.025};
  EXPECT_EQ(o.Check(2).message(),
            "time_offset.given_s: must be empty or have one entry per slave (2), got 1");
}

// The OnlineCalibrator on a rig pushed in capture order (lossless, refinements on stream time).
RigEstimate RunOnline(const FreeRunningRig& rig, const std::function<int64_t(int, int64_t)>& offset,
                      bool free_running) {
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.time_offset.enabled = free_running;
  OnlineCalibrator calibrator({"master", "cam1", "cam2"}, options);
  calibrator.Start();
  for (const CameraPose& p : InCaptureOrder(rig, offset)) calibrator.Push(p);
  calibrator.Flush();
  calibrator.RefineNow(/*final=*/true);
  calibrator.Stop();
  return calibrator.Estimate();
}

void ExpectWithinSigma(const SlaveCalibration& s, const Similarity& truth) {
  ASSERT_TRUE(s.usable()) << s.name << ": " << s.message;
  const CalibrationError e = CompareToTruth(s.estimate, truth);
  EXPECT_LE(e.rot_deg, kSigmas * std::sqrt(3.0) * s.rot_std_deg) << s.name;
  EXPECT_LE(e.trans_err, kSigmas * s.pos_std.norm()) << s.name;
}

TEST(OnlineTimeOffset, FreeRunningRigIsCalibratedAsWellAsSynchronised) {
  DriveOptions options;
  options.seed = 8;
  const std::vector<double> offsets = {0.060, -0.100};
  const FreeRunningRig free = Rig({{20.0, 0.019}, {30.0, 0.007}}, 60.0, options);
  const FreeRunningRig synchronised = Rig({{}, {}}, 60.0, options);
  const RigEstimate a = RunOnline(free, Constant(offsets), true);
  const RigEstimate b = RunOnline(synchronised, Constant({0.0, 0.0}), false);
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& s = a.rig.slaves[i];
    SCOPED_TRACE(s.name);
    ASSERT_TRUE(std::isfinite(s.time_offset_std_s));
    EXPECT_LE(std::abs(s.time_offset_s - offsets[i]), kSigmas * s.time_offset_std_s)
        << s.time_offset_s;
    EXPECT_TRUE(a.online[i].clock_offset_known && a.online[i].clock_offset_estimated);
    ExpectWithinSigma(s, free.truth[i]);
    EXPECT_LE(s.rot_std_deg, 1.5 * b.rig.slaves[i].rot_std_deg);
    EXPECT_LE(s.pos_std.norm(), 1.5 * b.rig.slaves[i].pos_std.norm());
    EXPECT_TRUE(std::isnan(b.rig.slaves[i].time_offset_s)) << "synchronised: no offset state";
  }
}

TEST(OnlineTimeOffset, SynchronisedStampsGiveZeroOffsetWithItsSigma) {
  DriveOptions options;
  options.seed = 9;
  const FreeRunningRig rig = Rig({{}, {}}, 40.0, options);
  const RigEstimate a = RunOnline(rig, Constant({0.0, 0.0}), true);
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& s = a.rig.slaves[i];
    ASSERT_TRUE(std::isfinite(s.time_offset_std_s)) << s.name;
    EXPECT_LE(std::abs(s.time_offset_s), kSigmas * s.time_offset_std_s) << s.name;
    ExpectWithinSigma(s, rig.truth[i]);
  }
}

// The clock offsets are a state of the estimator: saved with it, restored by a resume (matching
// starts at the saved offsets, no new initial search), and a state without them (cameras
// synchronised before, or an older state file) starts the search afresh.
TEST(OnlineTimeOffset, OffsetsAreSavedAndRestoredWithTheState) {
  DriveOptions drive;
  drive.seed = 14;
  const std::vector<double> offsets = {0.045, -0.070};
  const FreeRunningRig rig = Rig({{20.0, 0.013}, {20.0, 0.029}}, 60.0, drive);
  const std::vector<CameraPose> poses = InCaptureOrder(rig, Constant(offsets));
  const int64_t half = rig.master.t_ns.front() + 30'000'000'000;
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.time_offset.enabled = true;
  RigEstimatorState saved;
  RigEstimate before;
  {
    OnlineCalibrator first({"master", "cam1", "cam2"}, options);
    first.Start();
    for (const CameraPose& p : poses) {
      if (p.t_ns < half) first.Push(p);
    }
    first.Flush();
    first.Stop();
    saved = first.SaveState();
    before = first.Estimate();
  }
  ASSERT_EQ(saved.clock_offsets.size(), 2u);
  OnlineCalibrator resumed({"master", "cam1", "cam2"}, options);
  ASSERT_TRUE(resumed.RestoreState(saved).ok());
  const RigEstimate restored = resumed.Estimate();
  for (int i = 0; i < 2; ++i) {
    SCOPED_TRACE("slave " + std::to_string(i));
    EXPECT_TRUE(saved.clock_offsets[i].initialised);
    EXPECT_TRUE(restored.online[i].clock_offset_known);
    // The saved state is the filter's at its last measurement; the estimate before the restart
    // was predicted to the newest master stamp, at most dt = two measurement windows and a motion
    // span later: the offset moved by the drift over dt, the variance grew by the drift's, the
    // drift walk's and the offset walk's over dt (ClockOffsetTracker's prediction). (A relative
    // tolerance on σ no longer holds: the offset walk over dt is as large as the honest σ.)
    const ClockOffsetOptions& o = options.time_offset;
    const double dt = 2.0 * o.measure_window_s + o.motion_span_s;
    const double drift = restored.online[i].clock_drift_ppm * 1e-6;
    const double drift_std = restored.online[i].clock_drift_std_ppm * 1e-6;
    EXPECT_NEAR(restored.rig.slaves[i].time_offset_s, before.rig.slaves[i].time_offset_s,
                std::abs(drift) * dt + 1e-9);
    // Var(dt) = P00 + 2 dt P01 + dt² P11 + walks, |P01| <= sqrt(P00 P11).
    const double sigma = restored.rig.slaves[i].time_offset_std_s;
    const double bound = std::pow(sigma + drift_std * dt, 2) +
                         std::pow(o.drift_walk_ppm_per_sqrt_s * 1e-6, 2) * dt * dt * dt / 3.0 +
                         std::pow(o.offset_walk_s_per_sqrt_s, 2) * dt;
    EXPECT_LE(sigma, before.rig.slaves[i].time_offset_std_s * (1.0 + 1e-9));
    EXPECT_LE(std::pow(before.rig.slaves[i].time_offset_std_s, 2), bound * (1.0 + 1e-9));
    EXPECT_EQ(restored.online[i].clock_drift_ppm, before.online[i].clock_drift_ppm);
  }
  // The second half: every slave in the sets from its first poses on (no initial search).
  resumed.Start();
  uint64_t pushed_second_half = 0;
  for (const CameraPose& p : poses) {
    if (p.t_ns >= half) pushed_second_half += resumed.Push(p) == PushResult::kAccepted;
  }
  resumed.Flush();
  resumed.RefineNow(/*final=*/true);
  resumed.Stop();
  EXPECT_GT(pushed_second_half, 0u);
  const RigEstimate after = resumed.Estimate();
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& s = after.rig.slaves[i];
    SCOPED_TRACE(s.name);
    EXPECT_TRUE(after.online[i].clock_offset_known);
    EXPECT_EQ(after.online[i].clock_jumps, 0);
    EXPECT_LE(std::abs(s.time_offset_s - offsets[i]), kSigmas * s.time_offset_std_s);
    ExpectWithinSigma(s, rig.truth[i]);
  }

  // A state without clock offsets: estimated afresh (not known right after the restore).
  RigEstimatorState old = saved;
  old.clock_offsets.clear();
  OnlineCalibrator fresh({"master", "cam1", "cam2"}, options);
  ASSERT_TRUE(fresh.RestoreState(old).ok());
  EXPECT_FALSE(fresh.Estimate().online[0].clock_offset_known);
  // A state whose clock offsets do not fit the rig is refused whole.
  RigEstimatorState wrong = saved;
  wrong.clock_offsets.pop_back();
  OnlineCalibrator refused({"master", "cam1", "cam2"}, options);
  const Status status = refused.RestoreState(wrong);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("1 saved, the rig has 2 slaves"), std::string::npos)
      << status.message();
}

}  // namespace
}  // namespace rigcal
