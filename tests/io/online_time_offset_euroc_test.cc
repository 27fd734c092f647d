// SPDX-License-Identifier: Apache-2.0
// The online estimator on the real EuRoC V1_02 trajectory with one camera's clock shifted and
// the cameras capturing at other phases: the offset is found within its σ and the extrinsics
// are as accurate as with synchronised stamps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "../calib/free_running_rig.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/online_calibrator.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::io {
namespace {

constexpr double kSigmas = 4.0;  // an estimate within kSigmas σ of the truth passes

// 20 Hz cameras along the EuRoC ground truth (200 Hz): camera c takes every 10th pose from
// sample `phase` on (a phase of 5 ms per sample).
free_running::FreeRunningRig EurocRig(const TimedTrajectory& body, const std::vector<int>& phases,
                                      const std::vector<Similarity>& rigs) {
  free_running::FreeRunningRig out;
  out.truth = rigs;
  for (size_t c = 0; c < phases.size(); ++c) {
    std::vector<int64_t> t_ns;
    std::vector<Pose> world;
    for (size_t k = static_cast<size_t>(phases[c]); k < body.size(); k += 10) {
      t_ns.push_back(body.t_ns[k]);
      world.push_back(body.poses[k]);
    }
    DriveOptions options;
    options.rotation_noise_deg = 0.03;
    options.seed = 40 + c;
    const std::string name = c == 0 ? "m" : "cam" + std::to_string(c);
    const SyntheticDrive drive =
        GenerateDriveAlong({"m", name}, {rigs[c == 0 ? 0 : c - 1]}, t_ns, world, options);
    if (c == 0) {
      out.master = free_running::ToTimed(name, t_ns, drive.recording.master, 0);
    } else {
      out.slaves.push_back(free_running::ToTimed(name, t_ns, drive.recording.slaves[0], 0));
    }
  }
  return out;
}

RigEstimate RunOnline(const free_running::FreeRunningRig& rig, const std::vector<double>& offsets,
                      bool free_running) {
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.time_offset.enabled = free_running;
  OnlineCalibrator calibrator({"m", "cam1", "cam2"}, options);
  calibrator.Start();
  const auto offset = [&](int slave, int64_t) { return std::llround(offsets[slave] * 1e9); };
  for (const CameraPose& p : free_running::InCaptureOrder(rig, offset)) calibrator.Push(p);
  calibrator.Flush();
  calibrator.RefineNow(/*final=*/true);
  calibrator.Stop();
  return calibrator.Estimate();
}

TEST(OnlineTimeOffset, RealEurocTrajectoryWithOneClockShifted) {
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
  const std::vector<Similarity> demo = DemoRig();
  const std::vector<Similarity> rigs = {demo[0], demo[1]};
  // cam1 captures 15 ms after the master and its clock reads 40 ms ahead; cam2 35 ms after,
  // on the master's clock.
  const std::vector<double> offsets = {0.040, 0.0};
  const free_running::FreeRunningRig rig = EurocRig(*body, {0, 3, 7}, rigs);
  const free_running::FreeRunningRig synchronised = EurocRig(*body, {0, 0, 0}, rigs);
  const RigEstimate free = RunOnline(rig, offsets, true);
  const RigEstimate sync = RunOnline(synchronised, {0.0, 0.0}, false);
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& s = free.rig.slaves[i];
    SCOPED_TRACE(s.name);
    ASSERT_TRUE(std::isfinite(s.time_offset_std_s));
    EXPECT_LE(std::abs(s.time_offset_s - offsets[i]), kSigmas * s.time_offset_std_s)
        << s.time_offset_s;
    ASSERT_TRUE(s.usable()) << s.message;
    const CalibrationError e = CompareToTruth(s.estimate, rigs[i]);
    EXPECT_LE(e.rot_deg, kSigmas * std::sqrt(3.0) * s.rot_std_deg);
    EXPECT_LE(e.trans_err, kSigmas * s.pos_std.norm());
    // As well determined as with synchronised cameras.
    const SlaveCalibration& t = sync.rig.slaves[i];
    ASSERT_TRUE(t.usable()) << t.message;
    EXPECT_LE(s.rot_std_deg, 1.5 * t.rot_std_deg);
    EXPECT_LE(s.pos_std.norm(), 1.5 * t.pos_std.norm());
  }
}

}  // namespace
}  // namespace rigcal::io
