// SPDX-License-Identifier: Apache-2.0
// Cameras that run free: interpolation at the master's instants (trajectory_interpolation.h)
// and the clock offsets estimated from the data (time_offset.h), on simulated rigs whose
// slaves capture at other rates and phases with clock offsets up to ±100 ms, and on the real
// EuRoC V1_02 trajectory with one camera's clock shifted.
#include "rigcal/io/time_offset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "../calib/free_running_rig.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/io/trajectory_interpolation.h"
#include "trajectory_fixtures.h"

namespace rigcal::io {
namespace {

using free_running::CameraClock;
using free_running::FreeRunningRig;
using ::testing::HasSubstr;

constexpr double kSigmas = 4.0;  // an estimate within kSigmas σ of the truth passes

std::vector<Similarity> TwoSlaves() {
  const std::vector<Similarity> demo = DemoRig();
  return {demo[0], demo[1]};
}

// σ of the extrinsic rotation and position errors of a usable slave against the truth.
void ExpectWithinSigma(const SlaveCalibration& s, const Similarity& truth) {
  ASSERT_TRUE(s.usable()) << s.name << ": " << s.message;
  const CalibrationError e = CompareToTruth(s.estimate, truth);
  EXPECT_LE(e.rot_deg, kSigmas * std::sqrt(3.0) * s.rot_std_deg) << s.name;
  EXPECT_LE(e.trans_err, kSigmas * s.pos_std.norm()) << s.name;
}

TEST(TrajectoryInterpolation, InterpolatesWithinSegmentsAndNotAcrossGaps) {
  // Stamps 0, 10, 20, 30 (segment 0), 40..70 segment 1, then a gap to 200.
  std::vector<int64_t> t = {0, 10, 20, 30, 40, 50, 60, 70, 200};
  const TimedTrajectory tr = trajectory_test::MakeTrajectory("cam", t);
  const int64_t gap = 3 * MedianInterval(tr.t_ns);
  ASSERT_EQ(MedianInterval(tr.t_ns), 10);
  const auto exact = InterpolatePose(tr, 20, gap);
  ASSERT_TRUE(exact);
  EXPECT_TRUE(exact->pose.q.isApprox(tr.poses[2].q, 0.0));
  const auto mid = InterpolatePose(tr, 15, gap);
  ASSERT_TRUE(mid);
  EXPECT_NEAR(AngleBetween(mid->pose.q, tr.poses[1].q), AngleBetween(mid->pose.q, tr.poses[2].q),
              1e-12);
  EXPECT_TRUE(mid->pose.C.isApprox(0.5 * (tr.poses[1].C + tr.poses[2].C)));
  EXPECT_FALSE(InterpolatePose(tr, 35, gap)) << "across the segment boundary 30|40";
  EXPECT_FALSE(InterpolatePose(tr, 100, gap)) << "across the gap 70..200";
  EXPECT_FALSE(InterpolatePose(tr, -1, gap));
  EXPECT_FALSE(InterpolatePose(tr, 201, gap));
}

TEST(TrajectoryInterpolation, SynchronisedStampsMatchAsByNearestStamp) {
  DriveOptions options;
  const FreeRunningRig rig =
      free_running::MakeFreeRunningRig({}, {{}, {}}, TwoSlaves(), 20.0, options);
  const auto nearest = MatchTrajectories(rig.master, rig.slaves, 5'000'000);
  std::vector<bool> interpolated;
  const auto free =
      MatchFreeRunning(rig.master, rig.slaves, {0, 300'000}, 5'000'000, {}, &interpolated);
  ASSERT_TRUE(nearest && free);
  EXPECT_THAT(interpolated, ::testing::ElementsAre(false, false));
  EXPECT_EQ(nearest->t_ns, free->t_ns);
  for (size_t s = 0; s < 2; ++s) {
    for (size_t k = 0; k < nearest->size(); ++k) {
      ASSERT_EQ(nearest->slaves[s].poses[k].q.coeffs(), free->slaves[s].poses[k].q.coeffs());
    }
  }
}

TEST(TrajectoryInterpolation, PhaseShiftedSlaveIsInterpolated) {
  DriveOptions options;
  options.rotation_noise_deg = 0.0;
  options.position_noise = 0.0;
  const FreeRunningRig rig =
      free_running::MakeFreeRunningRig({}, {{20.0, 0.017, 0.0}}, {DemoRig()[0]}, 20.0, options);
  EXPECT_FALSE(MatchTrajectories(rig.master, rig.slaves, 5'000'000));  // 17 ms > tolerance
  std::vector<bool> interpolated;
  const auto matched = MatchFreeRunning(rig.master, rig.slaves, {0}, 5'000'000, {}, &interpolated);
  ASSERT_TRUE(matched) << matched.error();
  EXPECT_THAT(interpolated, ::testing::ElementsAre(true));
  EXPECT_GE(matched->size(), rig.master.size() - 2);
}

struct OffsetCase {
  std::vector<CameraClock> clocks;
};

class FreeRunningRigTest : public ::testing::TestWithParam<OffsetCase> {};

TEST_P(FreeRunningRigTest, OffsetsWithinSigmaAndExtrinsicsAsSynchronised) {
  DriveOptions options;
  options.seed = 5;
  const std::vector<CameraClock>& clocks = GetParam().clocks;
  const FreeRunningRig rig =
      free_running::MakeFreeRunningRig({}, clocks, TwoSlaves(), 60.0, options);
  CalibrationOptions calibration;
  const auto matched =
      MatchWithTimeOffsets(rig.master, rig.slaves, std::nullopt, 5'000'000, calibration);
  ASSERT_TRUE(matched) << matched.error();
  const RigCalibration result = CalibrateRig(matched->recording, calibration);
  const FreeRunningRig synchronised =
      free_running::MakeFreeRunningRig({}, {{}, {}}, TwoSlaves(), 60.0, options);
  const auto sync_matched = MatchTrajectories(synchronised.master, synchronised.slaves, 0);
  ASSERT_TRUE(sync_matched);
  const RigCalibration sync_result = CalibrateRig(*sync_matched, calibration);
  for (size_t i = 0; i < clocks.size(); ++i) {
    const TimeOffsetEstimate& o = matched->offsets[i];
    SCOPED_TRACE(rig.slaves[i].name + " true offset " + std::to_string(clocks[i].offset_s));
    ASSERT_TRUE(std::isfinite(o.std_s));
    EXPECT_GT(o.std_s, 0.0);
    EXPECT_LE(std::abs(o.offset_s - clocks[i].offset_s), kSigmas * o.std_s) << o.offset_s;
    ExpectWithinSigma(result.slaves[i], rig.truth[i]);
    // As well determined as with synchronised stamps.
    EXPECT_LE(result.slaves[i].rot_std_deg, 1.5 * sync_result.slaves[i].rot_std_deg);
    EXPECT_LE(result.slaves[i].pos_std.norm(), 1.5 * sync_result.slaves[i].pos_std.norm());
  }
}

INSTANTIATE_TEST_SUITE_P(Clocks, FreeRunningRigTest,
                         ::testing::Values(OffsetCase{{{20.0, 0.017, 0.040},
                                                       {30.0, 0.005, -0.100}}},
                                           OffsetCase{{{20.0, 0.031, 0.100}, {20.0, 0.0, -0.063}}},
                                           OffsetCase{{{30.0, 0.011, 0.0}, {20.0, 0.025, 0.0}}}));

TEST(TimeOffset, SynchronisedStampsGiveZeroOffsetAndTheSameExtrinsics) {
  DriveOptions options;
  options.seed = 9;
  const FreeRunningRig rig =
      free_running::MakeFreeRunningRig({}, {{}, {}}, TwoSlaves(), 60.0, options);
  CalibrationOptions calibration;
  const auto nearest = MatchTrajectories(rig.master, rig.slaves, 5'000'000);
  const auto matched =
      MatchWithTimeOffsets(rig.master, rig.slaves, std::nullopt, 5'000'000, calibration);
  ASSERT_TRUE(nearest && matched) << (matched ? "" : matched.error());
  const RigCalibration today = CalibrateRig(*nearest, calibration);
  const RigCalibration with_offsets = CalibrateRig(matched->recording, calibration);
  for (size_t i = 0; i < 2; ++i) {
    const TimeOffsetEstimate& o = matched->offsets[i];
    ASSERT_TRUE(std::isfinite(o.std_s));
    EXPECT_LE(std::abs(o.offset_s), kSigmas * o.std_s);
    EXPECT_FALSE(matched->interpolated[i]);
    EXPECT_EQ(today.slaves[i].estimate.q.coeffs(), with_offsets.slaves[i].estimate.q.coeffs());
    EXPECT_EQ(today.slaves[i].estimate.C, with_offsets.slaves[i].estimate.C);
  }
}

// The timing check (CheckGivenTimeOffsets) of slaves matched at offset 0, with the calibration at
// that match: what it found per slave.
RigCalibration Checked(const TimedTrajectory& master, const std::vector<TimedTrajectory>& slaves,
                       std::vector<std::string>* found) {
  const std::vector<std::optional<double>> given(slaves.size(), 0.0);
  const auto matched = MatchWithTimeOffsets(master, slaves, given, 5'000'000, CalibrationOptions{});
  EXPECT_TRUE(matched) << matched.error();
  if (!matched) return {};
  RigCalibration result = CalibrateRig(matched->recording, CalibrationOptions{});
  *found = CheckGivenTimeOffsets(master, slaves, given, {}, &result);
  return result;
}

// The demo drive (60 s, one slow period at 20 Hz), cam2's stamps `late_ns` late: little angular
// acceleration, a weak timing signal.
RigCalibration CheckedDemoDrive(int64_t late_ns, std::vector<std::string>* found) {
  const SyntheticDrive drive = GenerateDrive({"master", "cam1", "cam2"}, DemoRig(), DriveOptions{});
  const RigRecording& rec = drive.recording;
  std::vector<TimedTrajectory> slaves;
  for (size_t i = 0; i < 2; ++i) {
    slaves.push_back(
        free_running::ToTimed(rec.slaves[i].name, rec.t_ns, rec.slaves[i], i == 1 ? late_ns : 0));
  }
  return Checked(free_running::ToTimed("master", rec.t_ns, rec.master, 0), slaves, found);
}

// The brisk free-running rig of the solve tests (40 s at 20 Hz), cam2's stamps `late_ns` late.
RigCalibration CheckedBriskDrive(int64_t late_ns, std::vector<std::string>* found) {
  DriveOptions options;
  options.seed = 3;
  const FreeRunningRig rig = free_running::MakeFreeRunningRig(
      {}, {{20.0, 0.0, 0.0}, {20.0, 0.0, static_cast<double>(late_ns) * 1e-9}}, TwoSlaves(), 40.0,
      options);
  return Checked(rig.master, rig.slaves, found);
}

// Comparing the master's frames with the slave interpolated between its own made the preferred
// offset lean midway between frames (26.5 ms at σ 1.9 ms on the synchronised demo drive), which a
// floor of 0.75 frame hid, and with it a slave 30 ms late. Synchronised slaves pass; a slave 30 ms
// (0.6 of a frame) or one frame late is flagged and not usable, with --time-offset auto suggested.
TEST(TimeOffset, CheckPassesSynchronisedSlavesAndFlagsStampsAFractionOfAFrameOff) {
  for (const auto& checked : {CheckedDemoDrive, CheckedBriskDrive}) {
    std::vector<std::string> found;
    RigCalibration result = checked(0, &found);
    EXPECT_TRUE(found.empty()) << found.front();
    for (const SlaveCalibration& s : result.slaves) EXPECT_TRUE(s.usable()) << s.message;
    for (const int64_t late_ns : {30'000'000, 50'000'000}) {
      SCOPED_TRACE(late_ns);
      result = checked(late_ns, &found);
      ASSERT_EQ(found.size(), 1u);
      EXPECT_THAT(found[0], HasSubstr("for 'cam2'"));
      EXPECT_THAT(found[0], HasSubstr("--time-offset auto"));
      ASSERT_EQ(result.slaves.size(), 2u);
      EXPECT_TRUE(result.slaves[0].usable()) << result.slaves[0].message;
      EXPECT_FALSE(result.slaves[1].usable());
    }
  }
}

TEST(TimeOffset, RealEurocTrajectoryWithOneClockShifted) {
  const std::string path =
      std::string(RIGCAL_SHARED_DATA_DIR) + "/trajectories/V102_groundtruth.csv";
  if (!std::filesystem::exists(path)) {
    const char* ci = std::getenv("CI");
    if (ci != nullptr && std::string(ci) == "true") FAIL() << path << " not found";
    GTEST_SKIP() << path << " not found";
  }
  TrajectoryReadOptions read;
  read.max_quaternion_norm_error = 1e-3;
  auto body = ReadTrajectory(path, read);
  ASSERT_TRUE(body) << body.error();
  // 20 Hz cameras along the ground truth (every 10th pose of 200 Hz).
  std::vector<int64_t> t_ns;
  std::vector<Pose> world;
  for (size_t k = 0; k < body->size(); k += 10) {
    t_ns.push_back(body->t_ns[k]);
    world.push_back(body->poses[k]);
  }
  DriveOptions options;
  options.rotation_noise_deg = 0.03;
  const std::vector<Similarity> rigs = TwoSlaves();
  const SyntheticDrive drive =
      GenerateDriveAlong({"m", "cam1", "cam2"}, rigs, t_ns, world, options);
  const TimedTrajectory master = free_running::ToTimed("m", t_ns, drive.recording.master, 0);
  const int64_t shift = 40'000'000;
  const std::vector<TimedTrajectory> slaves = {
      free_running::ToTimed("cam1", t_ns, drive.recording.slaves[0], shift),
      free_running::ToTimed("cam2", t_ns, drive.recording.slaves[1], 0)};
  CalibrationOptions calibration;
  const auto matched = MatchWithTimeOffsets(master, slaves, std::nullopt, 5'000'000, calibration);
  ASSERT_TRUE(matched) << matched.error();
  const double truth[] = {1e-9 * static_cast<double>(shift), 0.0};
  const RigCalibration result = CalibrateRig(matched->recording, calibration);
  for (size_t i = 0; i < 2; ++i) {
    const TimeOffsetEstimate& o = matched->offsets[i];
    SCOPED_TRACE(slaves[i].name);
    ASSERT_TRUE(std::isfinite(o.std_s));
    EXPECT_LE(std::abs(o.offset_s - truth[i]), kSigmas * o.std_s) << o.offset_s;
    ExpectWithinSigma(result.slaves[i], rigs[i]);
  }
}

TEST(TimeOffset, BadInputIsAClearError) {
  DriveOptions options;
  FreeRunningRig rig = free_running::MakeFreeRunningRig({}, {{}}, {DemoRig()[0]}, 20.0, options);
  // A slave 30 s late: no overlap within ±0.5 s.
  FreeRunningRig late = rig;
  for (int64_t& t : late.slaves[0].t_ns) t += 30'000'000'000;
  const auto no_overlap = CorrelateAngularSpeed(late.master, late.slaves[0]);
  ASSERT_FALSE(no_overlap);
  EXPECT_THAT(no_overlap.error(), HasSubstr("'cam1'"));
  EXPECT_THAT(no_overlap.error(), HasSubstr("overlap"));
  // Too few poses.
  FreeRunningRig few = rig;
  few.slaves[0].t_ns.resize(5);
  few.slaves[0].poses.resize(5);
  few.slaves[0].segment.resize(5);
  const auto too_few =
      MatchWithTimeOffsets(few.master, few.slaves, std::nullopt, 5'000'000, CalibrationOptions{});
  ASSERT_FALSE(too_few);
  EXPECT_THAT(too_few.error(), HasSubstr("'cam1' has 5 poses"));
}

}  // namespace
}  // namespace rigcal::io
