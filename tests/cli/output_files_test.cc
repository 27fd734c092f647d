// SPDX-License-Identifier: Apache-2.0
// One rule for every file a command writes (tools/cli/output_files.h, docs/usage.md "Output
// files"), through the built binary, command by command: an existing file is replaced without
// --force, keeping its permissions; a path that is not a regular file (a directory) is never
// replaced; and every such command says so in its --help.
#include <sys/stat.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "cli/command_test.h"
#include "cli/synth_trajectories.h"
#include "support/simulated_rig_config.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using cli_test::RunResult;
using cli_test::Slurp;

struct OutputCase {
  const char* option;   // what the row covers
  std::string command;  // the arguments; OUT stands for the output path
};

class OutputFilesTest : public cli_test::SynthLogTest {
 protected:
  void SetUp() override {
    SynthLogTest::SetUp();
    if (HasFatalFailure()) return;
    cli_test::WriteSynthTrajectories(dir_);
    std::ofstream(Path("sim.yaml")) << support::SimulatedRigConfig(160, 120, 10);
    const RunResult result = Run("replay " + Path("poses.lcmlog") + " --config " +
                                 Path("rig.yaml") + " --no-progress -o " + Path("result.yaml"));
    ASSERT_EQ(result.exit_code, 0) << result.Explain();
  }

  std::vector<OutputCase> Cases() const {
    const std::string rig = " --config " + Path("rig.yaml");
    const std::string log = Path("poses.lcmlog");
    const std::string solve =
        "solve --master " + Path("front.txt") + " --slave " + Path("left.txt");
    const std::string tum = "import tum front=" + Path("front.txt") + " left=" + Path("left.txt");
    return {
        {"solve --out", solve + " -o OUT"},
        {"solve --camchain", solve + " --camchain OUT"},
        {"replay --out", "replay " + log + rig + " --no-progress -o OUT"},
        {"replay --camchain", "replay " + log + rig + " --no-progress --camchain OUT"},
        {"calib --out", "calib --log " + log + rig + " -o OUT"},
        {"synth-log --out", "synth-log" + rig + " --frames 100 -o OUT"},
        {"synth-log --truth-out",
         "synth-log" + rig + " --frames 100 -o " + Path("x.lcmlog") + " --truth-out OUT"},
        {"report --out", "report " + Path("result.yaml") + " -o OUT"},
        {"record --out",
         "record --config " + Path("sim.yaml") + " --no-vo --fast --image-encoding jpeg -o OUT"},
        {"import tum --out", tum + " --config-out " + Path("i.yaml") + " -o OUT"},
        {"import tum --config-out", tum + " -o " + Path("i.lcmlog") + " --config-out OUT"},
    };
  }

  static std::string With(std::string command, const std::string& out) {
    const size_t at = command.find("OUT");
    return command.replace(at, 3, cli_test::Quote(out));
  }
};

TEST_F(OutputFilesTest, EveryCommandReplacesAnExistingFileKeepingItsPermissions) {
  int n = 0;
  for (const OutputCase& c : Cases()) {
    const std::string out = Path("out" + std::to_string(n++));
    std::ofstream(out) << "an earlier output\n";
    fs::permissions(out, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
    const RunResult r = Run(With(c.command, out));
    EXPECT_EQ(r.exit_code, 0) << c.option << "\n" << r.Explain();
    const std::string text = Slurp(out);
    EXPECT_FALSE(text.empty()) << c.option;
    EXPECT_EQ(text.find("an earlier output"), std::string::npos) << c.option << ": not replaced";
    EXPECT_EQ(fs::status(out).permissions() & fs::perms::all,
              fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read)
        << c.option << ": permissions not kept";
  }
}

TEST_F(OutputFilesTest, APathThatIsNotARegularFileIsNeverReplaced) {
  int n = 0;
  for (const OutputCase& c : Cases()) {
    const std::string out = Path("dir" + std::to_string(n++));
    fs::create_directory(out);
    std::ofstream(out + "/keep") << "kept\n";
    const RunResult r = Run(With(c.command, out));
    EXPECT_EQ(r.exit_code, 1) << c.option << "\n" << r.Explain();
    EXPECT_NE(r.err.find(out), std::string::npos) << c.option << ": the path is not named\n"
                                                  << r.Explain();
    EXPECT_EQ(Slurp(out + "/keep"), "kept\n") << c.option;
  }
}

TEST_F(OutputFilesTest, EveryCommandThatWritesFilesStatesTheRuleInItsHelp) {
  for (const char* command : {"solve", "run", "calib", "replay", "synth-log", "report", "record",
                              "import", "import tum", "import euroc", "intrinsics", "vo"}) {
    const RunResult r = Run(std::string(command) + " --help");
    EXPECT_EQ(r.exit_code, 0) << command;
    EXPECT_NE(r.out.find("Output files: an existing file of the same name is replaced"),
              std::string::npos)
        << command << "\n"
        << r.out;
  }
}

}  // namespace
}  // namespace rigcal
