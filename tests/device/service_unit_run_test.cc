// SPDX-License-Identifier: Apache-2.0
// rigcal-run.service's own command line on v4l2loopback cameras, one of which stalls (issue 35
// §3): the ExecStart= of the configured unit (config/systemd/rigcal-run.service.in as installed,
// packed into the guest by tests/device/CMakeLists.txt) is expanded as systemd would with the
// unit's Environment=, of which only what /etc/default/rigcal may set is changed: RIGCAL_CONFIG
// (a rig of the two loopback cameras), RIGCAL_LCM_URL (an LCM log file: the guest has no
// network) and RIGCAL_LCM_OPTIONS (empty, as for a bus on this host); /var/lib/<StateDirectory=>
// becomes a directory of the test, the program the guest's rigcal. The test provides what
// systemd provides a Type=notify service: NOTIFY_SOCKET (a datagram socket it binds),
// WATCHDOG_USEC from WatchdogSec=, STATE_DIRECTORY.
//
// A writer feeds both cameras (the simulated rig of loopback_rig.h, a frame every
// RIGCAL_DEVICE_SERVICE_PERIOD_MS, default 500: several times the VO median of a 320x240 frame
// under emulation) until both VOs have initialised and two pings have come since. Checked:
// - READY=1 once; from it until the stall systemd never waits WatchdogSec for a WATCHDOG=1,
//   also while the VOs initialise (frames flow, no set is owed to the estimator yet; the master
//   VO of this drive needs ~40 s of frames here);
// - after cam1's writer stops, cam0 flowing on, every WATCHDOG=1 comes at the latest
//   --camera-timeout after cam1's last frame left its VO: the last write, plus one frame waiting
//   in the queue and one VO step (two periods); the writer then feeds cam0 for WatchdogSec more
//   without a ping (systemd's watchdog would have fired); the journal names cam1, not cam0;
// - SIGTERM: STOPPING=1, an exit systemd counts as success (0 or SuccessExitStatus=) within
//   TimeoutStopSec=, the state in the state directory whole with the sets the estimator took.
// The timings are printed as a RIGCAL-FIGURE line.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "guest_skip.h"
#include "loopback_rig.h"
#include "loopback_writer.h"
#include "notify_socket.h"
#include "rigcal/io/estimator_state_file.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/text_file.h"
#include "rigcal/sim/simulated_rig.h"
#include "service_unit.h"

extern char** environ;

namespace rigcal {
namespace {

using device_test::NotifySocket;
using Clock = NotifySocket::Clock;

double Seconds(Clock::duration d) { return std::chrono::duration<double>(d).count(); }

std::string FileText(const std::string& path) {
  auto text = io::ReadWholeFile(path);
  return text.ok() ? *text : std::string();
}

// The child's environment: the test's (LD_LIBRARY_PATH of the guest), then `extra` over it.
std::vector<std::string> ChildEnvironment(const std::map<std::string, std::string>& extra) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    if (extra.count(entry.substr(0, entry.find('='))) == 0) env.push_back(entry);
  }
  for (const auto& [key, value] : extra) env.push_back(key + "=" + value);
  return env;
}

// A child process: argv with env, stderr to a file; killed (SIGKILL) if still running at the end.
class Child {
 public:
  Child(const std::vector<std::string>& argv, const std::vector<std::string>& env,
        const std::string& err_path) {
    std::vector<char*> args, envp;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
    args.push_back(nullptr);
    envp.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err_path.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (posix_spawn(&pid_, argv[0].c_str(), &actions, nullptr, args.data(), envp.data()) != 0) {
      pid_ = -1;
    }
    posix_spawn_file_actions_destroy(&actions);
  }
  ~Child() {
    if (pid_ > 0 && Running()) {
      kill(pid_, SIGKILL);
      Wait(60.0);
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  pid_t pid() const { return pid_; }
  bool Running() {
    if (exit_code_ >= 0 || pid_ <= 0) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) != pid_) return true;
    exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return false;
  }
  // Waits up to `limit_s`; the exit code (128 + signal), or -1 if still running.
  int Wait(double limit_s) {
    const auto deadline = Clock::now() + std::chrono::duration<double>(limit_s);
    while (Running() && Clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return exit_code_;
  }

 private:
  pid_t pid_ = -1;
  int exit_code_ = -1;
};

// The value after `option` in argv, or `fallback`.
std::string OptionValue(const std::vector<std::string>& argv, const std::string& option,
                        const std::string& fallback) {
  const auto it = std::find(argv.begin(), argv.end(), option);
  return it != argv.end() && it + 1 != argv.end() ? *(it + 1) : fallback;
}

// The unit's ExecStart= for this guest (see the top of the file), printed.
std::vector<std::string> GuestCommandLine(const device_test::ServiceUnit& unit,
                                          const std::map<std::string, std::string>& env,
                                          const std::string& rigcal, const std::string& state_dir) {
  std::vector<std::string> argv = unit.ExpandExecStart(env);
  const std::string unit_state_dir = "/var/lib/" + unit.Setting("StateDirectory");
  std::cout << "ExecStart of the unit: " << unit.exec_start << "\nin the guest:";
  for (std::string& word : argv) {
    for (size_t at; (at = word.find(unit_state_dir)) != std::string::npos;) {
      word.replace(at, unit_state_dir.size(), state_dir);
    }
  }
  if (!argv.empty()) argv[0] = rigcal;
  for (const std::string& word : argv) std::cout << " " << word;
  std::cout << "\n";
  return argv;
}

struct Pings {
  std::vector<double> before_stall_s;  // WATCHDOG=1 arrival, seconds after the stall (negative)
  std::vector<double> after_stall_s;
};

Pings PingsAround(const NotifySocket& notify, Clock::time_point stall) {
  Pings pings;
  for (const Clock::time_point t : notify.Times("WATCHDOG=1")) {
    (t <= stall ? pings.before_stall_s : pings.after_stall_s).push_back(Seconds(t - stall));
  }
  return pings;
}

// The longest wait for WATCHDOG=1 from READY=1 to `until` (systemd's watchdog runs from READY=1).
double LongestPingGapS(const NotifySocket& notify, Clock::time_point until) {
  const std::vector<Clock::time_point> ready = notify.Times("READY=1");
  if (ready.empty()) return std::numeric_limits<double>::infinity();
  Clock::time_point last = ready[0];
  double longest = 0.0;
  for (const Clock::time_point t : notify.Times("WATCHDOG=1")) {
    if (t < last || t > until) continue;
    longest = std::max(longest, Seconds(t - last));
    last = t;
  }
  return std::max(longest, Seconds(until - last));
}

// Both VOs initialised (the estimator takes sets) and two pings since then: the state will hold
// motions.
bool EstimatorFed(const NotifySocket& notify, const std::string& err_path,
                  Clock::time_point* initialised) {
  if (*initialised == Clock::time_point{}) {
    const std::string err = FileText(err_path);
    if (err.find("camera 0: initialised") == std::string::npos ||
        err.find("camera 1: initialised") == std::string::npos) {
      return false;
    }
    *initialised = Clock::now();
  }
  int pings = 0;
  for (const Clock::time_point t : notify.Times("WATCHDOG=1")) pings += t > *initialised ? 1 : 0;
  return pings >= 2;
}

// The unit's command line for the guest and what the test needs of the unit.
struct ServiceRun {
  device_test::ServiceUnit unit;
  double watchdog_s = 0.0;      // WatchdogSec=
  double stop_limit_s = 0.0;    // TimeoutStopSec=
  double camera_timeout_s = 0;  // --camera-timeout of ExecStart=
  std::string dir, state_dir, state_path, err_path;
  std::map<std::string, std::string> env;
  std::vector<std::string> argv;
};

void PrepareRun(const std::string& unit_path, const std::string& rigcal, ServiceRun* run) {
  auto read = device_test::ReadServiceUnit(unit_path);
  ASSERT_TRUE(read.ok()) << read.error();
  run->unit = *read;
  const device_test::ServiceUnit& unit = run->unit;
  EXPECT_EQ(unit.Setting("Type"), "notify");
  run->watchdog_s = device_test::SystemdSpanSeconds(unit.Setting("WatchdogSec"));
  run->stop_limit_s = device_test::SystemdSpanSeconds(unit.Setting("TimeoutStopSec"));
  ASSERT_TRUE(run->watchdog_s > 0.0 && run->stop_limit_s > 0.0) << "WatchdogSec=, TimeoutStopSec=";
  run->dir = "/tmp/service_unit_run";
  run->state_dir = run->dir + "/state";
  run->err_path = run->dir + "/stderr.txt";
  std::filesystem::remove_all(run->dir);
  std::filesystem::create_directories(run->state_dir);
  std::filesystem::permissions(run->state_dir,
                               std::filesystem::perms(0750));  // StateDirectoryMode=
  run->env = unit.environment;                                 // changed as /etc/default/rigcal may
  run->env["RIGCAL_CONFIG"] = run->dir + "/rig.yaml";
  run->env["RIGCAL_LCM_URL"] = "file://" + run->dir + "/bus.lcm?mode=w";
  run->env["RIGCAL_LCM_OPTIONS"] = "";
  run->argv = GuestCommandLine(unit, run->env, rigcal, run->state_dir);
  run->camera_timeout_s = std::stod(OptionValue(run->argv, "--camera-timeout", "5"));
  run->state_path = OptionValue(run->argv, "--state", "");
  ASSERT_EQ(run->state_path.rfind(run->state_dir, 0), 0u) << "--state outside the state directory";
}

// After SIGTERM: STOPPING=1, an exit systemd counts as success within TimeoutStopSec=, the state
// whole with the sets the estimator took, the result written.
void CheckStop(const ServiceRun& run, const NotifySocket& notify, int exit_code) {
  const std::string success = run.unit.Setting("SuccessExitStatus");
  EXPECT_TRUE(exit_code == 0 || (exit_code > 0 && success == std::to_string(exit_code)))
      << "exit " << exit_code << " (-1: still running after TimeoutStopSec=" << run.stop_limit_s
      << " s)";
  EXPECT_EQ(notify.Times("STOPPING=1").size(), 1u) << "STOPPING=1 after SIGTERM";
  auto state_text = io::ReadWholeFile(run.state_path);
  ASSERT_TRUE(state_text.ok()) << state_text.error();
  auto state = io::ParseEstimatorState(*state_text);
  ASSERT_TRUE(state.ok()) << run.state_path << ": " << state.error();
  ASSERT_EQ(state->slaves.size(), 1u);
  ASSERT_EQ(state->consumed_t_ns.size(), 2u);
  EXPECT_GE(std::min(state->consumed_t_ns[0], state->consumed_t_ns[1]), 0)
      << "the saved state holds none of the sets the estimator took";
  EXPECT_TRUE(std::filesystem::exists(OptionValue(run.argv, "--out", ""))) << "no result file";
}

// When the phases of the test were.
struct Phases {
  Clock::time_point started;   // rigcal started
  Clock::time_point stall;     // cam1's last frame written
  int flowing_frames = 0;      // frames written to both cameras
  double period_s = 0.0;       // between frames
  double latest_ping_s = 0.0;  // after the stall, the last WATCHDOG=1 allowed
  double stopped_s = 0.0;      // SIGTERM to exit
  double longest_gap_s = 0.0;  // between pings while both cameras flowed
};

// READY=1 once before the stall; after it, no WATCHDOG=1 later than allowed; the log names cam1.
void CheckWatchdog(const ServiceRun& run, const NotifySocket& notify, const Phases& phases,
                   const std::string& err) {
  const std::vector<Clock::time_point> ready = notify.Times("READY=1");
  const Pings pings = PingsAround(notify, phases.stall);
  ASSERT_EQ(ready.size(), 1u) << "READY=1 messages";
  EXPECT_LT(ready[0], phases.stall);
  const double last_ping_s = pings.after_stall_s.empty() ? 0.0 : pings.after_stall_s.back();
  std::cout << "RIGCAL-FIGURE service_unit_watchdog: READY=1 " << Seconds(ready[0] - phases.started)
            << " s after start; " << pings.before_stall_s.size() << " WATCHDOG=1 in "
            << phases.flowing_frames << " frames of both cameras (period " << phases.period_s
            << " s, longest wait " << phases.longest_gap_s << " s); cam1 stalled: last WATCHDOG=1 "
            << last_ping_s << " s after its last frame (" << pings.after_stall_s.size()
            << " after it; camera timeout " << run.camera_timeout_s << " s, WatchdogSec "
            << run.watchdog_s << " s: systemd restarts by " << last_ping_s + run.watchdog_s
            << " s); stopped " << phases.stopped_s << " s after SIGTERM\n";
  EXPECT_LE(last_ping_s, phases.latest_ping_s) << "WATCHDOG=1 went on after cam1 stalled";
  EXPECT_NE(err.find("camera 'cam1' stalled"), std::string::npos) << "the log names cam1";
  EXPECT_EQ(err.find("camera 'cam0' stalled"), std::string::npos) << "cam0 flowed on";
}

TEST(ServiceUnitRun, WatchdogStopsWhenACameraStalls) {
  RIGCAL_REQUIRE_NODE("/dev/video20");
  RIGCAL_REQUIRE_NODE("/dev/video21");
  const char* rigcal = std::getenv("RIGCAL_DEVICE_RIGCAL");
  const char* unit_path = std::getenv("RIGCAL_DEVICE_FILE_RIGCAL_RUN_SERVICE");
  if (rigcal == nullptr || access(rigcal, X_OK) != 0 || unit_path == nullptr) {
    RIGCAL_SKIP_MISSING() << "no rigcal binary or rigcal-run.service in the guest "
                          << "(RIGCAL_DEVICE_RIGCAL, RIGCAL_DEVICE_FILE_RIGCAL_RUN_SERVICE; "
                          << "scripts/vm/run-device-tests.sh packs RIGCAL_VM_BINARIES and "
                          << "RIGCAL_VM_FILES)";
  }
  ServiceRun run;
  ASSERT_NO_FATAL_FAILURE(PrepareRun(unit_path, rigcal, &run));
  const char* period_env = std::getenv("RIGCAL_DEVICE_SERVICE_PERIOD_MS");
  const double period_s = (period_env ? std::atof(period_env) : 500.0) * 1e-3;
  ASSERT_GT(period_s, 0.0);
  const int width = 320, height = 240, frames = 240;
  const std::string simulated = device_test::SimulatedLoopbackRigYaml(width, height, frames);
  std::ofstream(run.dir + "/simulated.yaml") << simulated;
  std::ofstream(run.env["RIGCAL_CONFIG"]) << device_test::V4l2LoopbackRigYaml(simulated);
  auto config = io::LoadRigConfig(run.dir + "/simulated.yaml");
  ASSERT_TRUE(config.ok()) << config.error();
  auto rig = sim::MakeSimulatedRig(*config->simulated_source);
  ASSERT_TRUE(rig.ok()) << rig.error();

  NotifySocket notify(run.dir + "/notify.sock");
  ASSERT_EQ(notify.error(), "");
  std::map<std::string, std::string> env = run.env;  // what systemd adds for Type=notify
  env["NOTIFY_SOCKET"] = notify.path();
  env["WATCHDOG_USEC"] = std::to_string(static_cast<int64_t>(run.watchdog_s * 1e6));
  env["STATE_DIRECTORY"] = run.state_dir;

  capture::LoopbackWriter writer0("/dev/video20", capture::PixelFormat::kGrey, width, height);
  capture::LoopbackWriter writer1("/dev/video21", capture::PixelFormat::kYuyv, width, height);
  ASSERT_EQ(writer0.error(), "");
  ASSERT_EQ(writer1.error(), "");
  int k = 0;
  auto write = [&](bool both) {
    EXPECT_TRUE(writer0.Write(writer0.Pack(rig->RenderFrame(0, k)))) << writer0.error();
    if (both) EXPECT_TRUE(writer1.Write(writer1.Pack(rig->RenderFrame(1, k)))) << writer1.error();
    ++k;
  };
  write(true);  // a loopback device offers its format to readers once its writer has written

  Child child(run.argv, ChildEnvironment(env), run.err_path);
  ASSERT_GT(child.pid(), 0) << "cannot start " << rigcal;
  const Clock::time_point started = Clock::now();

  // Both cameras flow, a frame a period, until the estimator has been taking sets for two pings.
  Clock::time_point stall = started, initialised{};
  while (k < frames * 3 / 4 && child.Running() &&
         !EstimatorFed(notify, run.err_path, &initialised)) {
    stall = Clock::now();
    write(true);
    std::this_thread::sleep_until(stall + std::chrono::duration<double>(period_s));
  }
  ASSERT_TRUE(child.Running()) << "rigcal ended while both cameras flowed:\n"
                               << FileText(run.err_path);
  ASSERT_TRUE(EstimatorFed(notify, run.err_path, &initialised))
      << "the estimator was not fed within " << k << " frames of both cameras:\n"
      << FileText(run.err_path);
  const int flowing_frames = k;
  // While both cameras flowed (the VOs initialising, then tracking) systemd never waited
  // WatchdogSec for a ping.
  const double longest_gap_s = LongestPingGapS(notify, stall);
  EXPECT_LT(longest_gap_s, run.watchdog_s) << "WATCHDOG=1 missing while both cameras flowed";

  // cam1 stalls; cam0 flows on past the latest ping allowed plus WatchdogSec.
  const double latest_ping_s = run.camera_timeout_s + 2.0 * period_s;
  const auto stall_end =
      stall + std::chrono::duration<double>(latest_ping_s + run.watchdog_s + 1.0);
  while (Clock::now() < stall_end && k < frames && child.Running()) {
    const Clock::time_point written = Clock::now();
    write(false);
    std::this_thread::sleep_until(written + std::chrono::duration<double>(period_s));
  }
  ASSERT_TRUE(child.Running()) << "rigcal ended after the stall";
  ASSERT_GE(Clock::now(), stall_end) << "the rig has too few frames for the stall phase";

  const Clock::time_point term = Clock::now();
  ASSERT_EQ(kill(child.pid(), SIGTERM), 0);
  const int exit_code = child.Wait(run.stop_limit_s);
  const double stopped_s = Seconds(Clock::now() - term);
  const std::string err = FileText(run.err_path);
  std::cout << "rigcal's log:\n" << err;

  const Phases phases{started,       stall,     flowing_frames, period_s,
                      latest_ping_s, stopped_s, longest_gap_s};
  CheckWatchdog(run, notify, phases, err);
  CheckStop(run, notify, exit_code);
}

}  // namespace
}  // namespace rigcal
