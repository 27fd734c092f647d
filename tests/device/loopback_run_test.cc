// SPDX-License-Identifier: Apache-2.0
// The customer's whole path through the real V4L2 API, driven by `rigcal run`: a simulated
// two-camera rig renders its frames, a writer feeds them to two v4l2loopback devices (GREY and
// YUYV), and `rigcal run` with `source.type: v4l2` captures them (mmap streaming, kernel stamps),
// runs VO per camera and the online calibrator, and writes its result and VO poses. The result
// must converge and be what the same rig gives with its frames straight from the renderer
// (`rigcal run --fast` on the simulated source, run after it on the same guest): within the live
// run's own σ. Both runs' errors against the simulated truth are printed as RIGCAL-FIGURE lines,
// with the ratio to their σ. (Against the truth itself the estimator's σ of this 12-s drive is
// optimistic: over ten seeds of the same rig in simulation the rotation error was 0.8 to 15 times
// its σ, median 2.7; the two runs share the scene and so the VO's errors of one drive.)
//
// Pacing: under software emulation VO takes hundreds of ms per frame. The writer paces itself
// by what the guest processes: it writes a frame twice the slower camera's VO median of
// rigcal's last status line (plus 100 ms for capture and the estimator) after the previous one,
// rendering the next frame meanwhile, so that frames are not dropped for a VO backlog (each
// backlog drop rigcal reports makes the margin grow by a quarter). The V4L2 source stamps loopback
// frames at DQBUF (v4l2loopback does not flag its stamps CLOCK_MONOTONIC), moments after their
// write; the test maps every pose stamp back to the frame written last before it, to score the run
// against the simulated truth.
//
// Size of the run (environment, set by the ctest entries in tests/device/CMakeLists.txt):
// RIGCAL_DEVICE_LOOPBACK_FRAMES (frames per camera), RIGCAL_DEVICE_LOOPBACK_WIDTH (pixels;
// height = 3/4 of it, 60-degree pinhole cameras). The simulated drive is the same 12 s
// trajectory whatever the frame count (the rate is frames / 12 s), so fewer frames mean more
// motion between frames. In simulation (`rigcal run --fast` on the same rig) the VO needs
// 320x240 or more to initialise and 20 frames a second on this drive to keep tracking (72 or 120
// frames leave too few motions, 200 over a shorter drive converge to 7 sigma of the rotation):
// 240 frames of 320x240 converge with 110 motions, rotation error 0.09 deg at sigma 0.07 deg.

#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <regex>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "guest_skip.h"
#include "loopback_rig.h"
#include "loopback_writer.h"
#include "rigcal/capture/v4l2_timestamp.h"
#include "rigcal/io/result_file.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/pipeline/run_evaluation.h"

extern char** environ;

namespace rigcal {
namespace {

// sqrt of the 99.9 % quantile of chi-square with 3 degrees of freedom: a 3-vector error with the
// given per-axis sigma stays within this many sigma (Mahalanobis) but once in a thousand runs.
constexpr double kChi3Sigma999 = 4.03;
constexpr double kNormal999 = 3.29;  // two-sided 99.9 % of a normal variable, in sigma

int EnvInt(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : fallback;
}

// What rigcal run's status lines say (one a second): VO median per camera, backlog drops.
class StatusReader {
 public:
  void Parse(const std::string& line) {
    // "cam0 trk s0 12.3ms 240f drop2 | cam1 ...": state, segment, VO median, frames, drops.
    static const std::regex camera(R"(\b(cam\d) (\w+) s\d+ ([0-9.]+)ms \d+f( drop(\d+))?)");
    std::lock_guard<std::mutex> lock(mutex_);
    for (auto it = std::sregex_iterator(line.begin(), line.end(), camera);
         it != std::sregex_iterator(); ++it) {
      const int i = (*it)[1].str() == "cam0" ? 0 : 1;
      vo_ms_[i] = std::stod((*it)[3].str());
      if ((*it)[5].matched) drops_[i] = std::stoll((*it)[5].str());
      ++lines_;
    }
  }
  int64_t Drops() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return drops_[0] + drops_[1];
  }
  double SlowerVoMs() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return std::max(vo_ms_[0], vo_ms_[1]);
  }
  int64_t lines() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return lines_;
  }

 private:
  mutable std::mutex mutex_;
  double vo_ms_[2] = {0.0, 0.0};
  int64_t drops_[2] = {0, 0};
  int64_t lines_ = 0;
};

// `rigcal run` as a child process, its stderr read line by line (printed, and parsed).
class RigcalRun {
 public:
  RigcalRun(const std::string& rigcal, const std::vector<std::string>& args, StatusReader* status)
      : status_(status) {
    int fds[2];
    if (pipe(fds) != 0) return;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
    posix_spawn_file_actions_addclose(&actions, fds[0]);
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(rigcal.c_str()));
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    if (posix_spawn(&pid_, rigcal.c_str(), &actions, nullptr, argv.data(), environ) != 0) {
      pid_ = -1;
    }
    posix_spawn_file_actions_destroy(&actions);
    close(fds[1]);
    reader_ = std::thread([this, fd = fds[0]] {
      FILE* in = fdopen(fd, "r");
      char buf[1024];
      while (in && std::fgets(buf, sizeof(buf), in)) {
        std::string line(buf);
        std::cout << "  rigcal: " << line << std::flush;
        status_->Parse(line);
      }
      if (in) fclose(in);
    });
  }
  ~RigcalRun() {
    if (pid_ > 0 && !exited_) {
      kill(pid_, SIGKILL);
      Wait();
    }
    if (reader_.joinable()) reader_.join();
  }
  bool started() const { return pid_ > 0; }
  bool Running() {
    if (exited_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    return !exited_;
  }
  // SIGINT (rigcal run's clean stop), then the exit code.
  int Stop() {
    if (Running()) kill(pid_, SIGINT);
    return Wait();
  }
  int Wait() {
    if (!exited_) {
      int status = 0;
      waitpid(pid_, &status, 0);
      exited_ = true;
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    }
    if (reader_.joinable()) reader_.join();
    return exit_code_;
  }

 private:
  StatusReader* status_;
  pid_t pid_ = -1;
  bool exited_ = false;
  int exit_code_ = -1;
  std::thread reader_;
};

// A pose of a trajectory file at stamp t_ns.
CameraPose PoseAt(int camera, int64_t t_ns, const TimedTrajectory& trajectory, size_t j) {
  CameraPose pose;
  pose.camera = camera;
  pose.t_ns = t_ns;
  pose.segment = trajectory.segment[j];
  pose.pose = trajectory.poses[j];
  return pose;
}

// A run's one slave and its errors against the simulated truth.
struct ScoredRun {
  SlaveCalibration slave;
  pipeline::SlaveEvaluation score;
  std::string table;  // pipeline::FormatEvaluation
};

Expected<ScoredRun> ScoreRun(const sim::SimulatedRig& rig,
                             const std::vector<std::vector<CameraPose>>& poses,
                             const std::string& result_path) {
  auto result = io::ReadResultFile(result_path);
  if (!result.ok()) return Error{result.error()};
  if (result->slaves.size() != 1) return Error{result_path + ": not one slave"};
  auto evaluation = pipeline::EvaluateRun(rig, poses, *result);
  if (!evaluation.ok()) return Error{evaluation.error()};
  if (evaluation->slaves.size() != 1) return Error{result_path + ": slave not scored"};
  if (result->slaves[0].scales.empty()) return Error{result_path + ": no scale"};
  return ScoredRun{result->slaves[0], evaluation->slaves[0],
                   pipeline::FormatEvaluation(*evaluation)};
}

// (C - C_true) / |C_true|, in the run's master units.
Eigen::Vector3d RelativeCError(const ScoredRun& run) {
  const Eigen::Vector3d& truth = run.score.truth_master_units.C;
  return (run.slave.estimate.C - truth) / truth.norm();
}

// (scale - true scale) / true scale of the scored segment (EvaluateRun's truth: the ratio of
// the two VO units fitted to the simulated trajectory).
double RelativeScaleError(const ScoredRun& run) {
  const double truth = run.score.truth_master_units.scale;
  return (run.slave.scales.back().scale - truth) / truth;
}

// The run's errors against the truth, in degrees, percent and its own σ (RIGCAL-FIGURE lines).
void PrintFigure(const std::string& name, int width, int height, int frames, double feed_s,
                 const ScoredRun& run) {
  const SlaveCalibration& s = run.slave;
  const Eigen::Vector3d c_err = s.estimate.C - run.score.truth_master_units.C;
  const double scale_sigma_pct = 100.0 * s.scales.back().std / run.score.truth_master_units.scale;
  std::cout << run.table << "RIGCAL-FIGURE " << name << " " << width << "x" << height << " "
            << frames << " frames in " << feed_s << " s: rot_deg=" << run.score.error.rot_deg
            << " (sigma " << s.rot_std_deg << ", " << run.score.error.rot_deg / s.rot_std_deg
            << " sigma) dir_deg=" << run.score.error.dir_deg
            << " dist_pct=" << run.score.error.dist_pct
            << " scale_pct=" << run.score.error.scale_pct << " (sigma " << scale_sigma_pct
            << " %) C error " << c_err.transpose() << " (" << c_err.cwiseQuotient(s.pos_std).norm()
            << " sigma)\n";
}

TEST(LoopbackRun, RigcalRunOnV4l2SourceCalibratesTheSimulatedRig) {
  RIGCAL_REQUIRE_NODE("/dev/video20");
  RIGCAL_REQUIRE_NODE("/dev/video21");
  const char* rigcal = std::getenv("RIGCAL_DEVICE_RIGCAL");
  if (rigcal == nullptr || access(rigcal, X_OK) != 0) {
    RIGCAL_SKIP_MISSING() << "no rigcal binary in the guest (RIGCAL_DEVICE_RIGCAL; "
                          << "scripts/vm/run-device-tests.sh packs RIGCAL_VM_BINARIES)";
  }
  const int frames = EnvInt("RIGCAL_DEVICE_LOOPBACK_FRAMES", 240);
  const int width = EnvInt("RIGCAL_DEVICE_LOOPBACK_WIDTH", 320) / 4 * 4;
  const int height = width * 3 / 4;
  ASSERT_GE(frames, 12);
  ASSERT_GE(width, 64);
  const std::string dir = "/tmp/loopback_run";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string simulated = device_test::SimulatedLoopbackRigYaml(width, height, frames);
  std::ofstream(dir + "/simulated.yaml") << simulated;
  std::ofstream(dir + "/v4l2.yaml") << device_test::V4l2LoopbackRigYaml(simulated);
  auto config = io::LoadRigConfig(dir + "/simulated.yaml");
  ASSERT_TRUE(config.ok()) << config.error();
  auto rig = sim::MakeSimulatedRig(*config->simulated_source);
  ASSERT_TRUE(rig.ok()) << rig.error();

  capture::LoopbackWriter writer0("/dev/video20", capture::PixelFormat::kGrey, width, height);
  capture::LoopbackWriter writer1("/dev/video21", capture::PixelFormat::kYuyv, width, height);
  ASSERT_EQ(writer0.error(), "");
  ASSERT_EQ(writer1.error(), "");
  // Frame k+1 is rendered while rigcal processes frame k (within the writer's period).
  auto render = [&](int k) {
    return std::make_pair(writer0.Pack(rig->RenderFrame(0, k)),
                          writer1.Pack(rig->RenderFrame(1, k)));
  };
  auto next = render(0);
  // A loopback device offers its format to readers once its writer has written.
  ASSERT_TRUE(writer0.Write(next.first)) << writer0.error();
  ASSERT_TRUE(writer1.Write(next.second)) << writer1.error();

  StatusReader status;
  RigcalRun run(rigcal,
                {"run", "--config", dir + "/v4l2.yaml", "--out", dir + "/result.yaml",
                 "--poses-out", dir + "/poses", "--status-every", "1"},
                &status);
  ASSERT_TRUE(run.started()) << "cannot start " << rigcal;
  // Streaming once the first status line is there (the devices are open by then).
  const auto start_deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (status.lines() == 0 && run.Running() &&
         std::chrono::steady_clock::now() < start_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(run.Running()) << "rigcal run ended before the first frame";
  ASSERT_GT(status.lines(), 0) << "rigcal run printed no status within 60 s";

  const auto started = std::chrono::steady_clock::now();
  std::vector<int64_t> write_ns(frames, 0);  // CLOCK_MONOTONIC just before frame k was written
  std::vector<double> periods_ms;
  double margin = 2.0;  // period / VO median
  int64_t drops_seen = 0;
  for (int k = 0; k < frames && run.Running(); ++k) {
    const auto written = std::chrono::steady_clock::now();
    write_ns[k] = capture::MonotonicNowNs();
    ASSERT_TRUE(writer0.Write(next.first)) << writer0.error();
    ASSERT_TRUE(writer1.Write(next.second)) << writer1.error();
    // The VO median hides its slow frames (keyframes, bundle adjustment); a backlog drop means
    // the margin was too small: it grows by a quarter on each.
    if (status.Drops() > drops_seen) {
      drops_seen = status.Drops();
      margin = std::min(4.0, margin * 1.25);
    }
    const double vo_ms = status.SlowerVoMs();
    const double period_ms = vo_ms > 0.0 ? std::max(150.0, margin * vo_ms + 100.0) : 1000.0;
    periods_ms.push_back(period_ms);
    if (k + 1 < frames) next = render(k + 1);
    std::this_thread::sleep_until(written +
                                  std::chrono::microseconds(static_cast<int64_t>(period_ms * 1e3)));
  }
  const double feed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::sort(periods_ms.begin(), periods_ms.end());
  std::cout << "  " << frames << " frames written in " << feed_s << " s, period ms median "
            << periods_ms[periods_ms.size() / 2] << " max " << periods_ms.back() << "\n";
  std::this_thread::sleep_for(std::chrono::milliseconds(static_cast<int64_t>(periods_ms.back())));
  const int exit_code = run.Stop();
  EXPECT_TRUE(exit_code == 0 || exit_code == 3) << "rigcal run exit " << exit_code;

  // The VO poses back on the simulation's clock: the frame written last before the stamp.
  std::vector<std::vector<CameraPose>> poses(2);
  for (int i = 0; i < 2; ++i) {
    auto trajectory = io::ReadTrajectory(dir + "/poses/cam" + std::to_string(i) + ".txt");
    ASSERT_TRUE(trajectory.ok()) << trajectory.error();
    for (size_t j = 0; j < trajectory->size(); ++j) {
      const auto after = std::upper_bound(write_ns.begin(), write_ns.end(), trajectory->t_ns[j]);
      if (after == write_ns.begin()) continue;
      poses[i].push_back(PoseAt(i, rig->FrameTimeNs(after - write_ns.begin() - 1), *trajectory, j));
    }
    std::cout << "  cam" << i << ": " << poses[i].size() << " VO poses of " << frames
              << " frames\n";
    EXPECT_GT(poses[i].size(), 0u) << "cam" << i << ": no VO pose";
  }
  auto live = ScoreRun(*rig, poses, dir + "/result.yaml");
  ASSERT_TRUE(live.ok()) << live.error();
  ASSERT_TRUE(live->slave.usable()) << "the calibration did not converge: " << live->slave.message;
  PrintFigure("loopback_run", width, height, frames, feed_s, *live);

  // The reference: the same simulated rig calibrated in this process's way, frames straight from
  // the renderer (`rigcal run --fast` on the simulated source), on the same guest.
  StatusReader reference_status;
  RigcalRun reference(rigcal,
                      {"run", "--config", dir + "/simulated.yaml", "--fast", "--out",
                       dir + "/reference.yaml", "--poses-out", dir + "/reference_poses"},
                      &reference_status);
  ASSERT_TRUE(reference.started()) << "cannot start " << rigcal;
  const int reference_exit = reference.Wait();
  ASSERT_TRUE(reference_exit == 0 || reference_exit == 3)
      << "reference run exit " << reference_exit;
  std::vector<std::vector<CameraPose>> reference_poses(2);
  for (int i = 0; i < 2; ++i) {
    auto trajectory = io::ReadTrajectory(dir + "/reference_poses/cam" + std::to_string(i) + ".txt");
    ASSERT_TRUE(trajectory.ok()) << trajectory.error();
    for (size_t j = 0; j < trajectory->size(); ++j) {
      reference_poses[i].push_back(PoseAt(i, trajectory->t_ns[j], *trajectory, j));
    }
  }
  auto in_process = ScoreRun(*rig, reference_poses, dir + "/reference.yaml");
  ASSERT_TRUE(in_process.ok()) << in_process.error();
  ASSERT_TRUE(in_process->slave.usable()) << "reference: " << in_process->slave.message;
  PrintFigure("loopback_run_reference", width, height, frames, 0.0, *in_process);

  // Through V4L2 the calibration is the simulated source's, within the live run's own σ:
  // the rotation within 4.03 σ of its largest axis, C's error relative to |C| in the Mahalanobis
  // sense with the per-axis σ, the scale's relative error within 3.29 σ. (Both runs share the
  // scene and its VO errors; what differs is frames dropped, stamps and how sets pair.)
  const SlaveCalibration& a = live->slave;
  const SlaveCalibration& b = in_process->slave;
  const double rot_diff_deg = a.estimate.q.angularDistance(b.estimate.q) * 180.0 / M_PI;
  ASSERT_TRUE(std::isfinite(a.rot_std_deg));
  EXPECT_LE(rot_diff_deg, kChi3Sigma999 * a.rot_std_deg)
      << "rotation " << rot_diff_deg << " deg from the simulated source's (sigma " << a.rot_std_deg
      << " deg)";
  if (live->score.position_observable && a.pos_std.allFinite()) {
    const double norm_a = live->score.truth_master_units.C.norm();
    const Eigen::Vector3d diff = RelativeCError(*live) - RelativeCError(*in_process);
    const double mahalanobis = diff.cwiseQuotient(a.pos_std / norm_a).norm();
    EXPECT_LE(mahalanobis, kChi3Sigma999) << "C's relative error differs by " << diff.transpose();
  }
  const double scale_err_a = RelativeScaleError(*live);
  const double scale_err_b = RelativeScaleError(*in_process);
  const double scale_sigma = a.scales.back().std / live->score.truth_master_units.scale;
  ASSERT_TRUE(std::isfinite(scale_err_a) && std::isfinite(scale_err_b));
  EXPECT_LE(std::abs(scale_err_a - scale_err_b), kNormal999 * scale_sigma)
      << "scale error " << scale_err_a << " vs the simulated source's " << scale_err_b << " (sigma "
      << scale_sigma << ")";
}

}  // namespace
}  // namespace rigcal
