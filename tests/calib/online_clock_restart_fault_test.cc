// SPDX-License-Identifier: Apache-2.0
// A free-running slave whose clock restarts during a drive (simulated rig, OnlineCalibrator):
// stamps that restart near 0 or step by seconds, beyond the ±0.5 s the offset is searched in,
// are followed by the SyncBuffer and the offset is re-acquired around the step; a small step
// back (8 frames) is found by the tracker itself; either way it is counted as one clock jump, the
// calibration stays as accurate as its σ says and the other slave is unaffected. A restart of the
// MASTER's clock (near 0, +1 h, -1.5 s) is followed too: every slave's offset moves by minus the
// step (a given one is estimated from then on), counted once on the master, the calibration goes
// on as accurate as its σ says.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>

#include "../calib/free_running_rig.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/base/logging.h"
#include "rigcal/calib/online_calibrator.h"

namespace rigcal {
namespace {

using free_running::CameraClock;
using free_running::FreeRunningRig;
using free_running::InCaptureOrder;
using free_running::MakeFreeRunningRig;

constexpr double kSigmas = 4.0;

struct RestartCase {
  const char* name;
  double new_offset_s;  // cam1's clock after the restart (30 ms before)
};

class OnlineClockRestart : public ::testing::TestWithParam<RestartCase> {};

TEST_P(OnlineClockRestart, OffsetIsReacquiredAndCountedAsAJump) {
  SetLogLevel(std::getenv("RIGCAL_TEST_LOG") ? std::getenv("RIGCAL_TEST_LOG") : "error");
  const RestartCase& c = GetParam();
  DriveOptions drive;
  drive.seed = 12;
  const std::vector<Similarity> demo = DemoRig();
  const FreeRunningRig rig = MakeFreeRunningRig({}, {{20.0, 0.011, 0.0}, {20.0, 0.023, 0.0}},
                                                {demo[0], demo[1]}, 70.0, drive);
  const int64_t restart = rig.master.t_ns.front() + 30'000'000'000;
  auto offset = [&](int slave, int64_t t) -> int64_t {
    if (slave == 1) return -20'000'000;
    return t < restart ? 30'000'000 : std::llround(c.new_offset_s * 1e9);
  };
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.time_offset.enabled = true;
  OnlineCalibrator calibrator({"master", "cam1", "cam2"}, options);
  calibrator.Start();
  for (const CameraPose& p : InCaptureOrder(rig, offset)) calibrator.Push(p);
  calibrator.Flush();
  calibrator.RefineNow(/*final=*/true);
  calibrator.Stop();
  const RigEstimate e = calibrator.Estimate();
  SetLogLevel("info");

  const SyncStats sync = calibrator.sync_stats();
  EXPECT_EQ(sync.cameras[1].clock_jumps, std::abs(c.new_offset_s - 0.030) > 0.5 ? 1u : 0u)
      << sync.BriefReport();
  EXPECT_EQ(sync.cameras[2].clock_jumps, 0u) << sync.BriefReport();
  const SlaveCalibration& restarted = e.rig.slaves[0];
  EXPECT_EQ(e.online[0].clock_jumps, 1);
  EXPECT_TRUE(e.online[0].clock_offset_known);
  ASSERT_TRUE(std::isfinite(restarted.time_offset_std_s));
  EXPECT_LE(std::abs(restarted.time_offset_s - c.new_offset_s),
            kSigmas * restarted.time_offset_std_s)
      << restarted.time_offset_s << " ± " << restarted.time_offset_std_s;
  EXPECT_LT(restarted.time_offset_std_s, 0.002);
  const SlaveCalibration& steady = e.rig.slaves[1];
  EXPECT_EQ(e.online[1].clock_jumps, 0);
  EXPECT_LE(std::abs(steady.time_offset_s + 0.020), kSigmas * steady.time_offset_std_s);
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& s = e.rig.slaves[i];
    ASSERT_TRUE(s.usable()) << s.name << ": " << s.message;
    const CalibrationError err = CompareToTruth(s.estimate, rig.truth[i]);
    EXPECT_LE(err.rot_deg, kSigmas * std::sqrt(3.0) * s.rot_std_deg) << s.name;
    EXPECT_LE(err.trans_err, kSigmas * s.pos_std.norm()) << s.name;
  }
}

INSTANTIATE_TEST_SUITE_P(Restarts, OnlineClockRestart,
                         ::testing::Values(RestartCase{"StampsRestartNearZero", -39.95},
                                           RestartCase{"BackTwoSeconds", 0.030 - 2.0},
                                           RestartCase{"BackFourHundredMs", 0.030 - 0.4},
                                           RestartCase{"AheadSevenHundredMs", 0.030 + 0.7},
                                           RestartCase{"AheadFiveSeconds", 0.030 + 5.0},
                                           RestartCase{"AheadOneHour", 3600.0}),
                         [](const ::testing::TestParamInfo<RestartCase>& info) {
                           return std::string(info.param.name);
                         });

struct MasterRestartCase {
  const char* name;
  double step_s;  // the master's new clock - its old one
  bool cam2_given;
};

class OnlineMasterClockRestart : public ::testing::TestWithParam<MasterRestartCase> {};

TEST_P(OnlineMasterClockRestart, EveryOffsetMovesByTheStepAndTheEstimateGoesOn) {
  SetLogLevel(std::getenv("RIGCAL_TEST_LOG") ? std::getenv("RIGCAL_TEST_LOG") : "error");
  const MasterRestartCase& c = GetParam();
  DriveOptions drive;
  drive.seed = 14;
  const std::vector<Similarity> demo = DemoRig();
  const FreeRunningRig rig = MakeFreeRunningRig({}, {{20.0, 0.011, 0.0}, {20.0, 0.023, 0.0}},
                                                {demo[0], demo[1]}, 70.0, drive);
  const int64_t restart = rig.master.t_ns.front() + 30'000'000'000;
  const double offsets[2] = {0.030, -0.020};
  std::vector<CameraPose> poses =
      InCaptureOrder(rig, [&](int slave, int64_t) { return std::llround(offsets[slave] * 1e9); });
  for (CameraPose& p : poses) {
    if (p.camera == 0 && p.t_ns >= restart) p.t_ns += std::llround(c.step_s * 1e9);
  }
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.time_offset.enabled = true;
  if (c.cam2_given) options.time_offset.given_s = {std::nullopt, offsets[1]};
  OnlineCalibrator calibrator({"master", "cam1", "cam2"}, options);
  calibrator.Start();
  for (const CameraPose& p : poses) calibrator.Push(p);
  calibrator.Flush();
  calibrator.RefineNow(/*final=*/true);
  calibrator.Stop();
  const RigEstimate e = calibrator.Estimate();
  SetLogLevel("info");

  const SyncStats sync = calibrator.sync_stats();
  EXPECT_EQ(sync.cameras[0].clock_jumps, 1u) << sync.BriefReport();
  EXPECT_EQ(sync.cameras[1].clock_jumps, 0u) << sync.BriefReport();
  EXPECT_EQ(sync.cameras[2].clock_jumps, 0u) << sync.BriefReport();
  EXPECT_EQ(e.master_clock_jumps, 1);
  EXPECT_EQ(e.rejected_sets, 0u) << "the estimator's time does not jump back";
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& s = e.rig.slaves[i];
    EXPECT_EQ(e.online[i].clock_jumps, 0) << s.name;
    EXPECT_TRUE(e.online[i].clock_offset_estimated) << s.name << " (a given one too, after it)";
    EXPECT_TRUE(e.online[i].clock_offset_known) << s.name;
    ASSERT_TRUE(std::isfinite(s.time_offset_std_s)) << s.name;
    const double truth = offsets[i] - c.step_s;
    EXPECT_LE(std::abs(s.time_offset_s - truth), kSigmas * s.time_offset_std_s)
        << s.name << ": " << s.time_offset_s << " ± " << s.time_offset_std_s << ", truth " << truth;
    EXPECT_LT(s.time_offset_std_s, 0.002) << s.name;
    ASSERT_TRUE(s.usable()) << s.name << ": " << s.message;
    const CalibrationError err = CompareToTruth(s.estimate, rig.truth[i]);
    EXPECT_LE(err.rot_deg, kSigmas * std::sqrt(3.0) * s.rot_std_deg) << s.name;
    EXPECT_LE(err.trans_err, kSigmas * s.pos_std.norm()) << s.name;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Restarts, OnlineMasterClockRestart,
    ::testing::Values(MasterRestartCase{"StampsRestartNearZero", -39.99, false},
                      MasterRestartCase{"AheadOneHour", 3600.0, false},
                      MasterRestartCase{"BackOneAndAHalfSeconds", -1.5, false},
                      MasterRestartCase{"BackOneAndAHalfSecondsCam2Given", -1.5, true}),
    [](const ::testing::TestParamInfo<MasterRestartCase>& info) {
      return std::string(info.param.name);
    });

}  // namespace
}  // namespace rigcal
