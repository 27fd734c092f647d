// SPDX-License-Identifier: Apache-2.0
// `rigcal replay` and `rigcal calib --log` through the built binary: the same log gives the same
// result bit for bit (and the same as calib --log), damage is reported with its byte offset,
// and the exit codes agree: 0 every slave usable, 3 nothing calibrated (with the reason), 1 bad
// input (a missing config), 2 usage (an unknown subcommand, named). `rigcal --version` exists.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli/command_test.h"

namespace {

namespace fs = std::filesystem;

using rigcal::cli_test::RunResult;
using rigcal::cli_test::Slurp;

using ReplayCommandTest = rigcal::cli_test::SynthLogTest;

TEST_F(ReplayCommandTest, SameLogSameResultAsCalibLog) {
  const std::string common = Path("poses.lcmlog") + " --config " + Path("rig.yaml") + " --json";
  const RunResult a = Run("replay " + common + " --out " + Path("a.yaml"));
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const RunResult b =
      Run("replay " + common + " --out " + Path("b.yaml") + " --camchain " + Path("chain.yaml"));
  ASSERT_EQ(b.exit_code, 0) << b.err;
  // The JSON result, bit for bit (the provenance names the command line and the date).
  EXPECT_EQ(rigcal::cli_test::JsonWithoutProvenance(a.out),
            rigcal::cli_test::JsonWithoutProvenance(b.out));
  EXPECT_NE(a.out.find("\"provenance\""), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("\"slaves\""), std::string::npos) << a.out;
  // The result YAML likewise, but for its provenance (result_provenance_test.cc).
  EXPECT_EQ(rigcal::cli_test::YamlWithoutProvenance(Slurp(Path("a.yaml"))),
            rigcal::cli_test::YamlWithoutProvenance(Slurp(Path("b.yaml"))));
  EXPECT_NE(Slurp(Path("chain.yaml")).find("T_cn_cnm1"), std::string::npos);
  // Not a terminal: plain progress lines, the last one at 100 %.
  EXPECT_NE(a.err.find("rigcal replay: 100%"), std::string::npos) << a.err;

  const RunResult calib = Run("calib --log " + Path("poses.lcmlog") + " --config " +
                              Path("rig.yaml") + " --out " + Path("calib.yaml"));
  ASSERT_EQ(calib.exit_code, 0) << calib.err;
  EXPECT_EQ(rigcal::cli_test::YamlWithoutProvenance(Slurp(Path("a.yaml"))),
            rigcal::cli_test::YamlWithoutProvenance(Slurp(Path("calib.yaml"))));
}

// A live session (the thesis 5.4 simulated rig through rendering and VO, not paced, so it
// drops nothing) recorded with --lcm file://: its replay gives the result the live run gave.
TEST_F(ReplayCommandTest, RecordedLiveRunReplaysToTheLiveResult) {
  const std::string config = std::string(RIGCAL_SOURCE_DIR) + "/config/sim_thesis_virtual.yaml";
  const RunResult live = Run("run --config " + config + " --fast --status-every 0 --lcm file://" +
                             Path("session.lcmlog") + "?mode=w --out " + Path("live.yaml"));
  ASSERT_EQ(live.exit_code, 0) << live.err;
  EXPECT_EQ(live.err.find("dropped"), std::string::npos) << live.err;
  const RunResult replay = Run("replay " + Path("session.lcmlog") + " --config " + config +
                               " --out " + Path("replayed.yaml"));
  ASSERT_EQ(replay.exit_code, 0) << replay.err;
  EXPECT_NE(replay.err.find("RIGCAL_STATUS"), std::string::npos) << replay.err;  // not replayed
  // The run's VO and status publishers share the file bus without damaging the log.
  EXPECT_EQ(replay.err.find("byte "), std::string::npos) << replay.err;
  EXPECT_EQ(rigcal::cli_test::YamlWithoutProvenance(Slurp(Path("live.yaml"))),
            rigcal::cli_test::YamlWithoutProvenance(Slurp(Path("replayed.yaml"))));
}

TEST_F(ReplayCommandTest, DamagedLogReportsTheByteOffsetAndStillWritesTheResult) {
  const auto size = fs::file_size(Path("poses.lcmlog"));
  fs::resize_file(Path("poses.lcmlog"), size - 10);
  const RunResult r = Run("replay " + Path("poses.lcmlog") + " --config " + Path("rig.yaml") +
                          " --out " + Path("cut.yaml"));
  EXPECT_EQ(r.exit_code, 0) << r.err;  // the undamaged part calibrates
  EXPECT_NE(r.err.find("poses.lcmlog: byte "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("truncated"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(Path("cut.yaml")));
}

TEST_F(ReplayCommandTest, NothingCalibratedExitsThreeWithTheReason) {
  std::ofstream(Path("empty.lcmlog")).close();
  RunResult r = Run("replay " + Path("empty.lcmlog") + " --config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("holds no events"), std::string::npos) << r.err;
  r = Run("calib --log " + Path("empty.lcmlog") + " --config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 3) << r.err;

  // Camera names that match nothing in the log.
  std::ofstream(Path("other.yaml")) << "rig: {name: other, master: a}\n"
                                       "cameras:\n"
                                       "  - name: a\n"
                                       "  - name: b\n";
  r = Run("replay " + Path("poses.lcmlog") + " --config " + Path("other.yaml"));
  EXPECT_EQ(r.exit_code, 3) << r.err;
  EXPECT_NE(r.err.find("no synchronised pose set"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cameras not in the config"), std::string::npos) << r.err;
}

TEST_F(ReplayCommandTest, ExitCodesAgreeAcrossCommands) {
  // A missing config is bad input (1), named, for every command that takes one.
  for (const std::string& command : {"replay " + Path("poses.lcmlog"), std::string("calib"),
                                     std::string("run"), std::string("synth-log --out x.log")}) {
    const RunResult r = Run(command + " --config " + Path("missing.yaml"));
    EXPECT_EQ(r.exit_code, 1) << command << ": " << r.err;
    EXPECT_NE(r.err.find("missing.yaml"), std::string::npos) << command << ": " << r.err;
  }
  RunResult r = Run("replay " + Path("missing.lcmlog") + " --config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("missing.lcmlog"), std::string::npos) << r.err;
  r = Run("solve --master " + Path("missing.txt") + " --slave " + Path("missing2.txt"));
  EXPECT_EQ(r.exit_code, 1) << r.err;

  // Usage errors (2): an unknown subcommand is named as one; a missing argument.
  r = Run("frobnicate --config x");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("unknown subcommand 'frobnicate'"), std::string::npos) << r.err;
  r = Run("replay --config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  r = Run("replay " + Path("poses.lcmlog") + " --config " + Path("rig.yaml") + " --from 5 --to 2");
  EXPECT_EQ(r.exit_code, 2) << r.err;

  r = Run("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_EQ(r.out.rfind("rigcal 0.", 0), 0u) << r.out;
}

// The version names the commit the binary was built from (taken at every build, not when the
// build was configured): in a git checkout, `git describe`'s hash is a prefix of HEAD's.
TEST_F(ReplayCommandTest, VersionNamesTheCheckedOutCommit) {
  const RunResult head = rigcal::cli_test::RunShell(
      "git -C " + rigcal::cli_test::Quote(RIGCAL_SOURCE_DIR) + " rev-parse HEAD", dir_);
  if (head.exit_code != 0 || head.out.size() < 40) {
    GTEST_SKIP() << "not built from a git checkout (or no git): the version has no commit";
  }
  const RunResult r = Run("--version");
  ASSERT_EQ(r.exit_code, 0);
  const size_t open = r.out.find('(');
  const size_t close = r.out.find(')', open);
  ASSERT_NE(close, std::string::npos) << "no `git describe` in " << r.out;
  std::string describe = r.out.substr(open + 1, close - open - 1);  // [tag-N-g]HASH[-dirty]
  if (describe.size() > 6 && describe.compare(describe.size() - 6, 6, "-dirty") == 0) {
    describe.resize(describe.size() - 6);
  }
  const size_t g = describe.rfind("-g");
  const std::string hash = g == std::string::npos ? describe : describe.substr(g + 2);
  ASSERT_GE(hash.size(), 7u) << r.out;
  EXPECT_EQ(head.out.rfind(hash, 0), 0u) << "version " << r.out << " but HEAD is " << head.out;
}

}  // namespace
