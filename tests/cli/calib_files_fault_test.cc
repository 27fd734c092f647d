// SPDX-License-Identifier: Apache-2.0
// `rigcal calib` / `replay` and the files they write, under faults: an --out that is not a
// regular file, a replaced file's permissions, a run that calibrated nothing, a state file that
// --resume rejects (its mode kept) or may not touch (a directory, symbolic link, FIFO, device),
// a --publish-lcm file that cannot take what is published (file size limit as a full disk, a
// missing directory), and SIGTERM / SIGHUP during a paced replay (result and state written).
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "cli/command_test.h"

namespace {

namespace fs = std::filesystem;

using rigcal::cli_test::Quote;
using rigcal::cli_test::RunResult;
using rigcal::cli_test::RunShell;
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
  // The names in the test's directory that start with `prefix`.
  std::vector<std::string> Named(const std::string& prefix) const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) {
      const std::string name = e.path().filename().string();
      if (name.rfind(prefix, 0) == 0) names.push_back(name);
    }
    return names;
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

// --resume on a state path that is not a regular file: refused as the writer refuses it (exit
// 1, the kind named), before anything is read, moved or written; no result either.
TEST_F(CalibFilesFault, ResumeRefusesAStatePathThatIsNotARegularFile) {
  const std::string dir = Path("dir.state");
  fs::create_directory(dir);
  std::ofstream(dir + "/inside") << "kept\n";
  std::ofstream(Path("target.state")) << "kept\n";
  fs::create_symlink(Path("target.state"), Path("link.state"));
  ASSERT_EQ(::mkfifo(Path("fifo.state").c_str(), 0600), 0);
  struct Case {
    std::string path;
    std::string kind;
  };
  std::vector<Case> cases = {{dir, "a directory"},
                             {Path("link.state"), "a symbolic link"},
                             {Path("fifo.state"), "a FIFO"}};
  // A device node of our own (a copy of /dev/null's numbers) where the system lets us make one.
  if (::mknod(Path("dev.state").c_str(), S_IFCHR | 0600, makedev(1, 3)) == 0) {
    cases.push_back({Path("dev.state"), "a character device"});
  } else {
    std::cerr << "no device node case: mknod: " << std::strerror(errno) << "\n";
  }
  for (const Case& c : cases) {
    const RunResult r = Replay(Path("poses.lcmlog"),
                               "--out " + Path("r.yaml") + " --state " + c.path + " --resume");
    EXPECT_EQ(r.exit_code, 1) << c.kind << "\n" << r.Explain();
    EXPECT_NE(r.err.find("--resume: cannot write '" + c.path + "': it is " + c.kind),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(fs::exists(Path("r.yaml"))) << c.kind;
  }
  EXPECT_TRUE(fs::is_directory(fs::symlink_status(dir)));
  EXPECT_EQ(Slurp(dir + "/inside"), "kept\n");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(Path("link.state"))));
  EXPECT_EQ(Slurp(Path("target.state")), "kept\n");
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(Path("fifo.state"))));
  for (const std::string& name : Named("")) {
    EXPECT_EQ(name.find(".rejected-"), std::string::npos) << name << " was set aside";
  }
}

// A rejected state of mode 0600 is set aside with its mode, and the run's own state written in
// its place is as private (not the default 0644).
TEST_F(CalibFilesFault, RejectedStateKeepsItsMode) {
  const std::string state = Path("s.state");
  std::ofstream(state) << "not a state\n";
  ASSERT_EQ(::chmod(state.c_str(), 0600), 0);
  const RunResult r =
      Replay(Path("poses.lcmlog"), "--out " + Path("r.yaml") + " --state " + state + " --resume");
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  const std::vector<std::string> asides = Named("s.state.rejected-");
  ASSERT_EQ(asides.size(), 1u) << r.err;
  EXPECT_EQ(Mode(Path(asides[0])), 0600u);
  EXPECT_EQ(Slurp(state).rfind("rigcal-estimator-state ", 0), 0u);
  EXPECT_EQ(Mode(state), 0600u);
}

// --publish-lcm file://... that cannot take the log: a file size limit (RLIMIT_FSIZE, SIGXFSZ
// ignored: every write past it fails with EFBIG, as on a full disk) and a directory that does
// not exist. Either is an error naming the file (exit 1), never "published N".
TEST_F(CalibFilesFault, PublishedLogThatCannotBeWrittenIsAnError) {
  const std::string log = Path("out.lcmlog");
  // 16 blocks (8 KiB in dash's 512-byte blocks, 16 KiB in bash's): the result file fits, the
  // published log (about 40 KB) does not.
  const RunResult full = RunShell("ulimit -f 16; trap '' XFSZ; exec " + Quote(binary_) +
                                      " replay " + Path("poses.lcmlog") + " --config " +
                                      Path("rig.yaml") + " --no-progress --out " + Path("r.yaml") +
                                      " --publish-lcm 'file://" + log + "?mode=w'",
                                  dir_);
  EXPECT_EQ(full.exit_code, 1) << full.Explain();
  EXPECT_NE(full.err.find("publishing failed: " + log + ": "), std::string::npos) << full.err;
  EXPECT_NE(full.err.find("bytes published reached the file"), std::string::npos) << full.err;
  EXPECT_EQ(full.err.find("RIGCAL_STATUS on file://"), std::string::npos) << full.err;
  EXPECT_EQ(full.err.find("result not written"), std::string::npos) << full.err;
  // Without the limit the same log is whole and the run succeeds.
  const RunResult whole =
      Replay(Path("poses.lcmlog"),
             "--out " + Path("r2.yaml") + " --publish-lcm 'file://" + log + "?mode=w'");
  EXPECT_EQ(whole.exit_code, 0) << whole.Explain();
  EXPECT_GT(fs::file_size(log), 16u * 1024u);

  // Without ?mode=w LCM opens the file for reading: refused at once (reading /dev/full, as an
  // output given without the option, never ended).
  const pid_t pid =
      Spawn(binary_,
            {"replay", Path("poses.lcmlog"), "--config", Path("rig.yaml"), "--no-progress", "--out",
             Path("r4.yaml"), "--publish-lcm", "file:///dev/full"},
            Path("err_full.txt"));
  ASSERT_GT(pid, 0);
  EXPECT_EQ(WaitExit(pid, std::chrono::seconds(30)), 1);
  EXPECT_NE(
      Slurp(Path("err_full.txt")).find("file:///dev/full: an output file:// URL needs ?mode=w"),
      std::string::npos)
      << Slurp(Path("err_full.txt"));

  const std::string missing = Path("no/such/dir/out.lcmlog");
  const RunResult r =
      Replay(Path("poses.lcmlog"),
             "--out " + Path("r3.yaml") + " --publish-lcm 'file://" + missing + "?mode=w'");
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  EXPECT_NE(r.err.find(missing), std::string::npos) << r.err;
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
