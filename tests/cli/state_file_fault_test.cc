// SPDX-License-Identifier: Apache-2.0
// The state file of `rigcal replay` / `calib` under faults, through the built binary: kill -9 at
// random moments while the state is saved over and over (the file is always a complete version
// and --resume takes it), replaying the same data after a resume (adds nothing), and a camera
// moved between two runs (the decalibration alarm, then the new mounting).
#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "calib/free_running_rig.h"
#include "cli/command_test.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/slave_state.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/estimator_state_file.h"
#include "rigcal/io/result_file.h"
#include "rigcal/lcm/pose_log.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;

using cli_test::RunResult;
using cli_test::Slurp;
using cli_test::Spawn;
using cli_test::WaitExit;

// The rig of SynthLogTest: front (master) and left.
const Similarity kLeft{Eigen::Quaterniond(0.9238795, 0, 0.3826834, 0).normalized(),
                       Eigen::Vector3d(0.3, 0.05, -0.2), 1.0};

class StateFileFault : public cli_test::CommandTest {
 protected:
  void SetUp() override {
    CommandTest::SetUp();
    if (HasFatalFailure()) return;
    // The state saved every 0.1 s of log time: a replay saves it hundreds of times.
    std::ofstream(Path("rig.yaml")) << "rig: {name: test, master: front}\n"
                                       "cameras:\n"
                                       "  - name: front\n"
                                       "  - name: left\n"
                                       "publish: {extrinsics_rate_hz: 2, status_rate_hz: 1}\n"
                                       "state: {save_interval_s: 0.1}\n";
  }

  // A drive of `frames` poses at 20 Hz; from `change_frame` on the slave sits at `moved`.
  void WriteLog(const std::string& name, int frames, int change_frame = -1,
                const Similarity& moved = Similarity{}) const {
    DriveOptions d;
    d.num_frames = frames;
    d.rotation_noise_deg = 0.05;
    d.position_noise = 0.002;
    d.change_frame = change_frame;
    if (change_frame >= 0) d.changed_rigs = {moved};
    const SyntheticDrive drive = GenerateDrive({"front", "left"}, {kLeft}, d);
    ASSERT_TRUE(lcm::WritePoseLog(Path(name), drive.recording).ok());
  }

  // The first `frames` sets of `rec` as an LCM pose log.
  void WriteLogPrefix(const std::string& name, const RigRecording& rec, size_t frames) const {
    RigRecording prefix = rec;
    frames = std::min(frames, rec.size());
    prefix.t_ns.resize(frames);
    std::vector<CameraTrack*> tracks = {&prefix.master};
    for (CameraTrack& slave : prefix.slaves) tracks.push_back(&slave);
    for (CameraTrack* t : tracks) {
      t->poses.resize(frames);
      if (!t->segment.empty()) t->segment.resize(frames);
    }
    ASSERT_TRUE(lcm::WritePoseLog(Path(name), prefix).ok());
  }

  RunResult Replay(const std::string& log, const std::string& extra) const {
    return Run("replay " + Path(log) + " --config " + Path("rig.yaml") + " --no-progress " + extra);
  }

  static SlaveCalibration Left(const std::string& result_path) {
    const Expected<RigCalibration> rig = io::ReadResultFile(result_path);
    EXPECT_TRUE(rig.ok()) << (rig.ok() ? "" : rig.error());
    if (!rig.ok() || rig->slaves.empty()) return {};
    return rig->slaves[0];
  }
};

// kill -9 at 100 random moments of a replay that saves its state every 0.1 s of log time (50
// saves per run): the state file is always a complete, checksum-valid version (the one
// before the run or one the run saved), and `--resume` takes it.
TEST_F(StateFileFault, KillNineWhileSavingLeavesACompleteState) {
  WriteLog("poses.lcmlog", 100);
  WriteLog("short.lcmlog", 40);
  const std::string state = Path("s.state");
  const std::vector<std::string> args = {"replay",        Path("poses.lcmlog"),
                                         "--config",      Path("rig.yaml"),
                                         "--no-progress", "--state",
                                         state,           "--out",
                                         Path("r.yaml")};
  // One whole run: how long a replay takes here, and the first good state.
  const auto start = std::chrono::steady_clock::now();
  const pid_t first = Spawn(binary_, args, Path("err_first.txt"));
  ASSERT_GT(first, 0);
  const int first_code = WaitExit(first, std::chrono::seconds(120));
  ASSERT_TRUE(first_code == 0 || first_code == 3) << first_code << Slurp(Path("err_first.txt"));
  const auto run_us = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::steady_clock::now() - start)
                          .count();
  ASSERT_TRUE(io::ParseEstimatorState(Slurp(state)).ok());

  constexpr int kTrials = 100;
  constexpr unsigned kSeed = 16;
  std::mt19937 random(kSeed);
  std::uniform_int_distribution<int64_t> moment(0, run_us);
  int killed_running = 0, resumed = 0;
  std::set<std::string> versions;
  for (int trial = 0; trial < kTrials; ++trial) {
    const pid_t pid = Spawn(binary_, args, Path("err.txt"));
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::microseconds(moment(random)));
    int status = 0;
    // Still running: killed, then reaped. Finished: this waitpid has reaped it already (waiting
    // again would wait for a child that no longer exists).
    if (::waitpid(pid, &status, WNOHANG) == 0) {
      ASSERT_EQ(::kill(pid, SIGKILL), 0);
      ++killed_running;
      WaitExit(pid, std::chrono::seconds(60));
    }
    const std::string after = Slurp(state);
    const Expected<RigEstimatorState> parsed = io::ParseEstimatorState(after);
    ASSERT_TRUE(parsed.ok()) << "trial " << trial << " (seed " << kSeed << "): " << parsed.error();
    EXPECT_EQ(parsed->cameras, (std::vector<std::string>{"front", "left"}));
    versions.insert(after);
    // Every 10th trial: --resume takes the file (and keeps it: nothing renamed aside).
    if (trial % 10 == 9) {
      const RunResult r =
          Replay("short.lcmlog", "--state " + state + " --resume --out " + Path("r_short.yaml"));
      EXPECT_NE(r.err.find("resumed from " + state), std::string::npos) << r.Explain();
      EXPECT_EQ(r.err.find(".rejected-"), std::string::npos) << r.Explain();
      ++resumed;
    }
  }
  // Left-over temporary files of killed saves are the only other files in the directory.
  int others = 0;
  for (const auto& e : fs::directory_iterator(dir_)) {
    const std::string name = e.path().filename().string();
    if (name.find(".rejected-") != std::string::npos) ++others;
  }
  EXPECT_EQ(others, 0);
  std::cout << "kill -9 trials: " << kTrials << " (" << killed_running
            << " killed while running, the others had finished), run " << run_us / 1000 << " ms, "
            << versions.size() << " distinct complete states seen, " << resumed << " resumed\n";
  EXPECT_GE(killed_running, kTrials / 2);
}

// Replaying the same poses after a resume adds nothing (the state remembers how far each camera
// was consumed): the motions and σ are those of a resume on no new data. Later poses are added.
TEST_F(StateFileFault, ReplayingTheSameDataAfterAResumeAddsNothing) {
  WriteLog("poses.lcmlog", 1200);
  const std::string state = "--state " + Path("s.state");
  ASSERT_EQ(Replay("poses.lcmlog", "--to 30 --out " + Path("a.yaml") + " " + state).exit_code, 0);
  const SlaveCalibration a = Left(Path("a.yaml"));
  ASSERT_GT(a.motions.used, 0);
  const std::string saved = Slurp(Path("s.state"));

  // The same 30 s again, resumed.
  const RunResult again =
      Replay("poses.lcmlog", "--to 30 --resume --out " + Path("b.yaml") + " " + state);
  ASSERT_EQ(again.exit_code, 0) << again.Explain();
  EXPECT_NE(again.err.find("are skipped"), std::string::npos) << again.err;
  const SlaveCalibration b = Left(Path("b.yaml"));
  // A resume on nothing new: the first half-second only (every pose consumed before).
  std::ofstream(Path("s2.state")) << saved;
  ASSERT_EQ(Replay("poses.lcmlog",
                   "--to 0.5 --resume --state " + Path("s2.state") + " --out " + Path("c.yaml"))
                .exit_code,
            0);
  const SlaveCalibration c = Left(Path("c.yaml"));
  EXPECT_EQ(b.motions.used, a.motions.used);  // without the consumed stamps: twice as many
  EXPECT_EQ(b.motions.used, c.motions.used);
  const auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  EXPECT_TRUE(same(b.rot_std_deg, c.rot_std_deg)) << b.rot_std_deg << " vs " << c.rot_std_deg;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(same(b.pos_std[i], c.pos_std[i])) << i;

  // The whole drive, resumed: the second half is new.
  ASSERT_EQ(Replay("poses.lcmlog", "--resume --out " + Path("d.yaml") + " " + state).exit_code, 0);
  const SlaveCalibration d = Left(Path("d.yaml"));
  EXPECT_GT(d.motions.used, a.motions.used + a.motions.used / 2);
}

// Cameras that run free (estimator.time_offset: auto): the slave's clock offset, its drift, σ
// and jump count are in the state file (version 5) and --resume goes on from them (no new
// initial search; the measurements accumulate).
TEST_F(StateFileFault, ClockOffsetsOfFreeRunningCamerasSurviveAResume) {
  std::ofstream(Path("rig.yaml"), std::ios::app) << "estimator: {time_offset: auto}\n";
  DriveOptions d;
  d.seed = 5;
  const free_running::FreeRunningRig rig =
      free_running::MakeFreeRunningRig({}, {{20.0, 0.019, 0.0}}, {kLeft}, 60.0, d);
  const std::vector<CameraPose> poses =
      free_running::InCaptureOrder(rig, [](int, int64_t) -> int64_t { return 40'000'000; });
  ASSERT_TRUE(lcm::WritePoseEvents(Path("free.lcmlog"), {"front", "left"}, poses).ok());
  const std::string state = "--state " + Path("s.state");
  const RunResult first = Replay("free.lcmlog", "--to 30 --out " + Path("a.yaml") + " " + state);
  ASSERT_EQ(first.exit_code, 0) << first.Explain();
  EXPECT_NE(first.err.find("time offset of 'left': initialised at"), std::string::npos)
      << first.Explain();
  const Expected<RigEstimatorState> saved = io::ParseEstimatorState(Slurp(Path("s.state")));
  ASSERT_TRUE(saved.ok()) << saved.error();
  ASSERT_EQ(saved->clock_offsets.size(), 1u);
  const ClockOffsetState& a = saved->clock_offsets[0];
  ASSERT_TRUE(a.initialised);
  EXPECT_NEAR(a.offset_s, 0.040, 0.001);
  EXPECT_GT(a.measurements, 0);
  EXPECT_GT(a.covariance(0, 0), 0.0);

  const RunResult resumed = Replay("free.lcmlog", "--resume --out " + Path("b.yaml") + " " + state);
  ASSERT_EQ(resumed.exit_code, 0) << resumed.Explain();
  EXPECT_NE(resumed.err.find("resumed from"), std::string::npos) << resumed.Explain();
  EXPECT_EQ(resumed.err.find("initialised at"), std::string::npos)
      << "the offset was searched afresh:\n"
      << resumed.Explain();
  const Expected<RigEstimatorState> after = io::ParseEstimatorState(Slurp(Path("s.state")));
  ASSERT_TRUE(after.ok()) << after.error();
  ASSERT_EQ(after->clock_offsets.size(), 1u);
  EXPECT_GT(after->clock_offsets[0].measurements, a.measurements);
  EXPECT_EQ(after->clock_offsets[0].jumps, 0);
  const SlaveCalibration b = Left(Path("b.yaml"));
  ASSERT_TRUE(std::isfinite(b.time_offset_std_s)) << b.message;
  EXPECT_LE(std::abs(b.time_offset_s - 0.040), 4.0 * b.time_offset_std_s) << b.time_offset_s;
}

// The slave camera is moved (5° about y and 5 cm) between two runs: the resumed run raises the
// decalibration alarm and ends at the new mounting.
TEST_F(StateFileFault, ACameraMovedBetweenRunsRaisesTheAlarmAndReconverges) {
  const Similarity moved{
      (kLeft.q * Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitY())).normalized(),
      kLeft.C + Eigen::Vector3d(0.05, 0.0, 0.0), 1.0};
  WriteLog("poses.lcmlog", 2400, /*change_frame=*/1200, moved);
  const std::string state = "--state " + Path("s.state");
  ASSERT_EQ(Replay("poses.lcmlog", "--to 60 --out " + Path("a.yaml") + " " + state).exit_code, 0);
  const SlaveCalibration a = Left(Path("a.yaml"));
  ASSERT_TRUE(a.usable()) << a.message;
  EXPECT_LT(AngleBetween(a.estimate.q, kLeft.q) * 180.0 / M_PI, 0.5);

  const RunResult r = Replay("poses.lcmlog", "--resume --out " + Path("b.yaml") + " " + state);
  EXPECT_NE(r.err.find("slave 'left' decalibrated"), std::string::npos) << r.Explain();
  const SlaveCalibration b = Left(Path("b.yaml"));
  // 60 s after the move the estimate follows the new mounting (its state may still say
  // decalibrated: the alarm clears once the short and long windows agree again).
  std::cout << "after the move: state " << ToString(b.state) << ": " << b.message << "\n";
  const double err_deg = AngleBetween(b.estimate.q, moved.q) * 180.0 / M_PI;
  const double old_deg = AngleBetween(b.estimate.q, kLeft.q) * 180.0 / M_PI;
  std::cout << "after the move: " << err_deg << " deg from the new mounting, " << old_deg
            << " deg from the old one\n";
  EXPECT_LT(err_deg, 1.0);
  EXPECT_GT(old_deg, 4.0);
}

// The slave camera moved and the alarm raised before a restart: `calib --log --resume` on the
// next seconds of the drive still reports the slave decalibrated (result, stderr, exit code 3),
// as the uninterrupted run does (the alarm holds for short_half_life_s, 20 s); before state
// version 7 the restarted estimator called it usable on the first new motion.
TEST_F(StateFileFault, ADecalibrationAlarmRaisedBeforeARestartIsReportedAfterIt) {
  const Similarity moved{
      (kLeft.q * Eigen::AngleAxisd(5.0 * M_PI / 180.0, Eigen::Vector3d::UnitY())).normalized(),
      kLeft.C + Eigen::Vector3d(0.05, 0.0, 0.0), 1.0};
  DriveOptions d;
  d.num_frames = 2400;  // 20 Hz: 120 s, the camera moved at 60 s
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  d.change_frame = 1200;
  d.changed_rigs = {moved};
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {kLeft}, d);
  ASSERT_TRUE(lcm::WritePoseLog(Path("poses.lcmlog"), drive.recording).ok());
  // When the alarm comes (it depends on the noise): the estimator alone on the same sets.
  RigEstimator alone({"front", "left"}, RigEstimatorOptions{});
  int alarm_s = -1;
  const RigRecording& rec = drive.recording;
  for (size_t k = 0; k < rec.size() && alarm_s < 0; ++k) {
    alone.AddSet(rec.t_ns[k], rec.SetAt(k));
    if (alone.Estimate().rig.slaves[0].state == SlaveState::kDecalibrated) {
      alarm_s = static_cast<int>((rec.t_ns[k] - rec.t_ns[0]) / 1'000'000'000) + 1;
    }
  }
  ASSERT_GE(alarm_s, 60) << "the move raised no alarm";
  // The first run stops a few seconds after it (the node's refinements may shift it a little:
  // the first of these ends that finds the slave decalibrated).
  const std::string state = " --state " + Path("s.state");
  int stop_s = 0;
  SlaveCalibration a;
  for (int to_s = alarm_s + 1; to_s <= alarm_s + 9 && a.state != SlaveState::kDecalibrated;
       to_s += 4) {
    fs::remove(Path("s.state"));
    const RunResult r =
        Replay("poses.lcmlog", "--to " + std::to_string(to_s) + " --out " + Path("a.yaml") + state);
    ASSERT_NE(r.exit_code, 1) << r.Explain();
    a = Left(Path("a.yaml"));
    stop_s = to_s;
  }
  ASSERT_EQ(a.state, SlaveState::kDecalibrated) << "no alarm by " << stop_s << " s: " << a.message;

  // The restart: the same drive up to 5 s later (the poses consumed before are skipped).
  WriteLogPrefix("more.lcmlog", drive.recording, static_cast<size_t>(stop_s + 5) * 20);
  const RunResult r = Run("calib --log " + Path("more.lcmlog") + " --config " + Path("rig.yaml") +
                          " --resume --out " + Path("b.yaml") + state);
  EXPECT_EQ(r.exit_code, 3) << r.Explain();
  EXPECT_NE(r.err.find("resumed from"), std::string::npos) << r.Explain();
  EXPECT_NE(r.err.find("left: decalibrated"), std::string::npos) << r.Explain();
  const SlaveCalibration b = Left(Path("b.yaml"));
  EXPECT_EQ(b.state, SlaveState::kDecalibrated) << b.message;
  EXPECT_GT(b.motions.used, a.motions.used) << "the resumed run took no new motion";
}

}  // namespace
}  // namespace rigcal
