// SPDX-License-Identifier: Apache-2.0
// The result YAML of `rigcal replay`, `calib --log` and `run` says where it came from (the
// `provenance:` block of io/provenance.h, as `solve --out` writes it): the rigcal version, the
// date, the command line, the config's path and every input with its size and hash; and the
// readers of result files (`report`, `solve --truth`/`--prior`) still take such a file.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <string>

#include "cli/command_test.h"
#include "cli/synth_trajectories.h"
#include "rigcal/io/provenance.h"

namespace rigcal {
namespace {

using cli_test::Quote;
using cli_test::RunResult;
using cli_test::Slurp;

class ResultProvenanceTest : public cli_test::SynthLogTest {
 protected:
  // The provenance block of a result YAML; fails the test when it is not there or incomplete.
  void ExpectProvenance(const std::string& result, const std::string& command,
                        const std::vector<std::string>& inputs) const {
    const YAML::Node root = YAML::LoadFile(result);
    const YAML::Node p = root["provenance"];
    ASSERT_TRUE(p && p.IsMap()) << result << ":\n" << Slurp(result);
    EXPECT_EQ(p["schema_version"].as<int>(), io::kResultSchemaVersion);
    EXPECT_EQ(p["rigcal"].as<std::string>().rfind("0.", 0), 0u) << p["rigcal"];
    EXPECT_EQ(p["date_utc"].as<std::string>().size(), 20u) << p["date_utc"];
    EXPECT_NE(p["command"].as<std::string>().find(command), std::string::npos) << p["command"];
    EXPECT_EQ(p["config"].as<std::string>(), Path("rig.yaml"));
    ASSERT_TRUE(p["inputs"].IsSequence());
    for (const std::string& input : inputs) {
      bool found = false;
      for (const YAML::Node& f : p["inputs"]) {
        if (f["path"].as<std::string>() != input) continue;
        found = true;
        EXPECT_GT(f["bytes"].as<int64_t>(), 0) << input;
        EXPECT_EQ(f["fnv1a64"].as<std::string>().size(), 16u) << input;
      }
      EXPECT_TRUE(found) << input << " not among the inputs of " << result;
    }
    EXPECT_TRUE(p["units"].IsMap());
    EXPECT_EQ(root["master"].as<std::string>(), "front") << Slurp(result);
    EXPECT_TRUE(root["left"].IsMap()) << Slurp(result);
  }
};

TEST_F(ResultProvenanceTest, ReplayAndCalibResultsSayWhereTheyCameFrom) {
  const std::string log = Path("poses.lcmlog");
  const RunResult replay = Run("replay " + Quote(log) + " --config " + Quote(Path("rig.yaml")) +
                               " --no-progress -o " + Quote(Path("replay.yaml")));
  ASSERT_EQ(replay.exit_code, 0) << replay.Explain();
  ExpectProvenance(Path("replay.yaml"), "rigcal replay " + log, {log, Path("rig.yaml")});
  const RunResult calib = Run("calib --log " + Quote(log) + " --config " + Quote(Path("rig.yaml")) +
                              " -o " + Quote(Path("calib.yaml")));
  ASSERT_EQ(calib.exit_code, 0) << calib.Explain();
  ExpectProvenance(Path("calib.yaml"), "rigcal calib --log " + log, {log, Path("rig.yaml")});

  // The readers of result files take them as before.
  const RunResult report =
      Run("report " + Quote(Path("replay.yaml")) + " -o " + Quote(Path("r.html")));
  EXPECT_EQ(report.exit_code, 0) << report.Explain();
  cli_test::WriteSynthTrajectories(dir_);
  const std::string solve =
      "solve --master " + Quote(Path("front.txt")) + " --slave " + Quote(Path("left.txt")) + " -q";
  const RunResult truth = Run(solve + " --truth " + Quote(Path("calib.yaml")));
  EXPECT_EQ(truth.exit_code, 0) << truth.Explain();
  EXPECT_NE(truth.out.find("left"), std::string::npos) << truth.out;
  const RunResult prior = Run(solve + " --prior " + Quote(Path("replay.yaml")));
  EXPECT_EQ(prior.exit_code, 0) << prior.Explain();
}

}  // namespace
}  // namespace rigcal
