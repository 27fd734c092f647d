// SPDX-License-Identifier: Apache-2.0
// One command-line grammar (issue 37 §6): verbosity anywhere, unknown words named with the
// nearest known one, -o on the commands that write, exit codes that agree, calib refusing a
// lossy file:// bus.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "cli/command_test.h"

namespace rigcal {
namespace {

using cli_test::Quote;
using cli_test::RunResult;
using ::testing::HasSubstr;
using ::testing::Not;

class CliGrammarTest : public cli_test::CommandTest {
 protected:
  std::string Config() const {
    return Quote(std::string(RIGCAL_SOURCE_DIR) + "/config/sim_thesis_virtual.yaml");
  }
};

TEST_F(CliGrammarTest, UnknownOptionIsNamedWithTheNearestOne) {
  const RunResult r = Run("solve --mastr cam0.txt --slave cam1.txt");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: unknown option '--mastr'; did you mean '--master'?"));
  EXPECT_THAT(r.err, Not(HasSubstr("is required")));
}

TEST_F(CliGrammarTest, UnknownSubcommandIsNamedWithTheNearestOne) {
  const RunResult r = Run("slove --master a.txt");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("unknown subcommand 'slove'; did you mean 'solve'?"));
  EXPECT_THAT(Run("frobnicate").err, Not(HasSubstr("did you mean")));
}

TEST_F(CliGrammarTest, VerbosityAnywhereOnTheLine) {
  ASSERT_EQ(Run("synth-log --config " + Config() + " -o " + Quote(Path("p.lcmlog"))).exit_code, 0);
  const std::string args = "replay " + Quote(Path("p.lcmlog")) + " --config " + Config() + " -o " +
                           Quote(Path("r.yaml"));
  const RunResult plain = Run(args);
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  EXPECT_THAT(plain.err, HasSubstr("[info]"));
  for (const std::string& quiet : {args + " -q", "-q " + args, args + " --log-level warn",
                                   "--log-level=warn " + args, args + " --quiet"}) {
    const RunResult r = Run(quiet);
    EXPECT_EQ(r.exit_code, 0) << quiet << ": " << r.err;
    EXPECT_THAT(r.err, Not(HasSubstr("[info]"))) << quiet;
  }
  const RunResult verbose = Run(args + " -v");
  EXPECT_EQ(verbose.exit_code, 0) << verbose.err;
  EXPECT_THAT(Run(args + " --log-level shout").err, HasSubstr("shout"));
}

TEST_F(CliGrammarTest, CalibRefusesALossyFileBus) {
  const RunResult r = Run("calib --config " + Config() + " --lcm " + Quote("file://x.lcmlog"));
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_THAT(r.err, HasSubstr("rigcal replay"));
}

TEST_F(CliGrammarTest, ExitCodesAgree) {
  // A missing input is bad input (1) for report as for every other command.
  const RunResult report =
      Run("report " + Quote(Path("missing.lcmlog")) + " -o " + Quote(Path("r.html")));
  EXPECT_EQ(report.exit_code, 1) << report.err;
  // A file that is not an LCM log is bad input (1) for replay.
  std::ofstream(Path("not_a_log.lcmlog")) << "hello, not a log\n";
  const RunResult replay =
      Run("replay " + Quote(Path("not_a_log.lcmlog")) + " --config " + Config());
  EXPECT_EQ(replay.exit_code, 1) << replay.err;
  EXPECT_THAT(replay.err, HasSubstr("not_a_log.lcmlog"));
}

}  // namespace
}  // namespace rigcal
