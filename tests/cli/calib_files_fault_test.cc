// SPDX-License-Identifier: Apache-2.0
// `rigcal calib` / `replay` and the files they write, under faults: an --out that is not a
// regular file, a replaced file's permissions, a run that calibrated nothing, a state file that
// --resume rejects, and SIGTERM / SIGHUP during a paced replay (result and state written).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "cli/command_test.h"

namespace {

namespace fs = std::filesystem;

using rigcal::cli_test::RunResult;
using rigcal::cli_test::Slurp;
using rigcal::cli_test::Spawn;
using rigcal::cli_test::WaitExit;

// The rig config and pose log of SynthLogTest.
class CalibFilesFault : public rigcal::cli_test::SynthLogTest {
 protected:
  RunResult Replay(const std::string& log, const std::string& extra) const {
    return Run("replay " + log + " --config " + Path("rig.yaml") + " --no-progress " + extra);
  }
  static unsigned Mode(const std::string& path) {
    struct stat st {};
    return ::stat(path.c_str(), &st) == 0 ? st.st_mode & 07777 : 0;
  }
};

TEST_F(CalibFilesFault, OutThatIsNotARegularFileIsRefused) {
  const std::string fifo = Path("fifo.yaml");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  RunResult r = Replay(Path("poses.lcmlog"), "--out " + fifo);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("'" + fifo + "': it is a FIFO, not a regular file"), std::string::npos)
      << r.err;
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));

  std::ofstream(Path("target.yaml")) << "kept\n";
  fs::create_symlink(Path("target.yaml"), Path("link.yaml"));
  r = Run("calib --log " + Path("poses.lcmlog") + " --config " + Path("rig.yaml") + " --out " +
          Path("link.yaml"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("it is a symbolic link"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(Path("link.yaml"))));
  EXPECT_EQ(Slurp(Path("target.yaml")), "kept\n");
}

TEST_F(CalibFilesFault, ReplacedResultAndStateKeepTheirPermissions) {
  const std::string files = "--out " + Path("r.yaml") + " --state " + Path("s.state");
  ASSERT_EQ(Replay(Path("poses.lcmlog"), files).exit_code, 0);
  EXPECT_EQ(Mode(Path("r.yaml")), 0644u);
  ASSERT_EQ(::chmod(Path("r.yaml").c_str(), 0600), 0);
  ASSERT_EQ(::chmod(Path("s.state").c_str(), 0640), 0);
  const RunResult r = Replay(Path("poses.lcmlog"), files);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(Mode(Path("r.yaml")), 0600u);
  EXPECT_EQ(Mode(Path("s.state")), 0640u);
}

TEST_F(CalibFilesFault, RunThatCalibratedNothingLeavesTheEarlierFiles) {
  const std::string files = "--out " + Path("r.yaml") + " --state " + Path("s.state");
  ASSERT_EQ(Replay(Path("poses.lcmlog"), files).exit_code, 0);
  const std::string result = Slurp(Path("r.yaml"));
  const std::string state = Slurp(Path("s.state"));
  ASSERT_NE(result.find("usable: true"), std::string::npos) << result;
  std::ofstream(Path("empty.lcmlog")).close();
  const RunResult r = Replay(Path("empty.lcmlog"), files);
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("calibrated nothing: " + Path("r.yaml") + " left as it was"),
            std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("calibrated nothing: " + Path("s.state") + " left as it was"),
            std::string::npos)
      << r.err;
  EXPECT_EQ(Slurp(Path("r.yaml")), result);
  EXPECT_EQ(Slurp(Path("s.state")), state);
  // Without earlier files the (empty) result is still written, as before.
  EXPECT_EQ(Replay(Path("empty.lcmlog"), "--out " + Path("new.yaml")).exit_code, 3);
  EXPECT_TRUE(fs::exists(Path("new.yaml")));
}

TEST_F(CalibFilesFault, RejectedStateIsKeptAsideNotOverwritten) {
  const std::string state = Path("s.state");
  for (const std::string& bad :
       {std::string("not a state\n"), std::string("rigcal-estimator-state 99\nchecksum 0\n")}) {
    for (const auto& e : fs::directory_iterator(dir_)) {
      if (e.path().filename().string().rfind("s.state", 0) == 0) fs::remove(e.path());
    }
    std::ofstream(state) << bad;
    const RunResult r =
        Replay(Path("poses.lcmlog"), "--out " + Path("r.yaml") + " --state " + state + " --resume");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("kept as " + state + ".rejected-"), std::string::npos) << r.err;
    int asides = 0;
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string name = e.path().filename().string();
      if (name.rfind("s.state.rejected-", 0) == 0) {
        ++asides;
        EXPECT_EQ(Slurp(e.path()), bad);
      }
    }
    EXPECT_EQ(asides, 1);
    // The run's own state is saved at the path and resumes.
    EXPECT_EQ(Slurp(state).rfind("rigcal-estimator-state ", 0), 0u);
  }
  // The state of another rig is rejected the same way.
  std::ofstream(Path("other.yaml")) << "rig: {name: other, master: front}\n"
                                       "cameras:\n"
                                       "  - name: front\n"
                                       "  - name: right\n";
  const RunResult other =
      Run("replay " + Path("poses.lcmlog") + " --config " + Path("other.yaml") +
          " --no-progress --state " + state + " --resume --out " + Path("o.yaml"));
  EXPECT_NE(other.err.find("kept as " + state + ".rejected-"), std::string::npos) << other.err;
}

TEST_F(CalibFilesFault, SigtermAndSighupWriteResultAndState) {
  for (const int signal : {SIGTERM, SIGHUP}) {
    const std::string tag = std::to_string(signal);
    const std::string out = Path("r" + tag + ".yaml");
    const std::string state = Path("s" + tag + ".state");
    const pid_t pid = Spawn(binary_,
                            {"replay", Path("poses.lcmlog"), "--config", Path("rig.yaml"),
                             "--speed", "1", "--no-progress", "--out", out, "--state", state},
                            Path("err" + tag + ".txt"));
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::seconds(4));  // a few seconds of log replayed
    ASSERT_EQ(::kill(pid, signal), 0);
    const int code = WaitExit(pid, std::chrono::seconds(60));
    const std::string err = Slurp(Path("err" + tag + ".txt"));
    // 0 when the slave is usable, 3 when not (the result says which).
    const bool usable = Slurp(out).find("usable: true") != std::string::npos;
    EXPECT_EQ(code, usable ? 0 : 3) << "signal " << signal << "\n" << err;
    EXPECT_NE(err.find("signal " + tag + " received: stopped cleanly"), std::string::npos) << err;
    EXPECT_NE(Slurp(out).find("\nleft:"), std::string::npos) << out;  // the slave's entry
    EXPECT_EQ(Slurp(state).rfind("rigcal-estimator-state ", 0), 0u) << state;
  }
}

}  // namespace
