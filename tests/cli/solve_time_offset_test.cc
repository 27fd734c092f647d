// SPDX-License-Identifier: Apache-2.0
// `rigcal solve --time-offset`: a rig whose slaves run free (other rates and phases, clock
// offsets) written as TUM files and solved by the built binary.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "calib/free_running_rig.h"
#include "cli/command_test.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal {
namespace {

using cli_test::Quote;
using cli_test::RunResult;
using ::testing::ContainsRegex;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kSigmas = 4.0;

class SolveTimeOffsetTest : public cli_test::CommandTest {
 protected:
  // Writes master.txt, cam1.txt, cam2.txt and truth.yaml; returns the solve arguments.
  std::string WriteRig(const std::vector<free_running::CameraClock>& clocks) {
    DriveOptions options;
    options.seed = 3;
    const std::vector<Similarity> demo = DemoRig();
    rig_ = free_running::MakeFreeRunningRig({}, clocks, {demo[0], demo[1]}, 40.0, options);
    std::string args = "solve --master " + Quote(Path("master.txt"));
    EXPECT_TRUE(io::WriteTrajectoryTum(Path("master.txt"), rig_.master).ok());
    std::map<std::string, Similarity> truth;
    for (size_t i = 0; i < rig_.slaves.size(); ++i) {
      const std::string path = Path(rig_.slaves[i].name + ".txt");
      EXPECT_TRUE(io::WriteTrajectoryTum(path, rig_.slaves[i]).ok());
      args += " --slave " + Quote(path);
      truth[rig_.slaves[i].name] = rig_.truth[i];
    }
    EXPECT_TRUE(io::WriteRigYaml(Path("truth.yaml"), truth).ok());
    return args + " --truth " + Quote(Path("truth.yaml")) + " --truth-unit master";
  }

  free_running::FreeRunningRig rig_;
};

std::string Explain(const RunResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\n--- stdout:\n" + r.out + "\n--- stderr:\n" +
         r.err;
}

TEST_F(SolveTimeOffsetTest, AutoEstimatesEverySlavesOffsetWithItsSigma) {
  const std::vector<free_running::CameraClock> clocks = {{20.0, 0.017, 0.060},
                                                         {30.0, 0.004, -0.090}};
  const std::string args = WriteRig(clocks);
  const RunResult r = Run(args + " --time-offset auto --json --out " + Quote(Path("out.yaml")));
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["slaves"].size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    const auto& s = j["slaves"][i];
    SCOPED_TRACE(s.dump());
    ASSERT_TRUE(s["time_offset_s"].is_number() && s["time_offset_std_s"].is_number());
    const double offset = s["time_offset_s"].get<double>();
    const double std = s["time_offset_std_s"].get<double>();
    EXPECT_GT(std, 0.0);
    EXPECT_LE(std::abs(offset - clocks[i].offset_s), kSigmas * std);
    EXPECT_LE(s["errors"]["rot_deg"].get<double>(),
              kSigmas * std::sqrt(3.0) * s["std"]["rot_deg"].get<double>());
  }
  EXPECT_THAT(cli_test::Slurp(Path("out.yaml")), HasSubstr("time_offset_std_s:"));
}

// Timing checked without --time-offset: a slave one frame late, or its clock 40 or 30 ms shifted
// (0.6 of a frame: the preferred offset was drawn midway between frames before), is
// not silently interpolated into a "converged" result: the data's preferred offset is named
// with its σ, --time-offset auto suggested, the slave not usable (exit 3). Synchronised slaves
// pass the check (exit 0).
TEST_F(SolveTimeOffsetTest, StampsOffWithoutTimeOffsetAreReportedNotConverged) {
  std::string args = WriteRig({{20.0, 0.0, 0.0}, {20.0, 0.0, 0.0}});
  RunResult r = Run(args + " --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  EXPECT_THAT(r.err, Not(HasSubstr("timing:")));
  for (const double late_s : {0.05, 0.04, 0.03}) {
    args = WriteRig({{20.0, 0.0, 0.0}, {20.0, 0.0, late_s}});
    r = Run(args + " --json");
    SCOPED_TRACE(late_s);
    EXPECT_EQ(r.exit_code, 3) << Explain(r);
    EXPECT_THAT(r.err, HasSubstr("timing: the data prefer a time offset of"));
    EXPECT_THAT(r.err, HasSubstr("for 'cam2'"));
    EXPECT_THAT(r.err, HasSubstr("--time-offset auto"));
    EXPECT_THAT(r.err, Not(HasSubstr("for 'cam1'")));
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_NE(j["slaves"][1]["state"].get<std::string>(), "converged");
    EXPECT_NE(j["slaves"][1]["state"].get<std::string>(), "usable");
  }
}

TEST_F(SolveTimeOffsetTest, GivenOffsetIsAppliedAndReportedWithoutSigma) {
  const std::string args = WriteRig({{20.0, 0.0, 0.050}, {20.0, 0.0, 0.050}});
  const RunResult r = Run(args + " --time-offset 0.05 --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const auto j = nlohmann::json::parse(r.out);
  for (const auto& s : j["slaves"]) {
    EXPECT_DOUBLE_EQ(s["time_offset_s"].get<double>(), 0.05);
    EXPECT_TRUE(s["time_offset_std_s"].is_null());
  }
}

TEST_F(SolveTimeOffsetTest, PerSlaveOffsetsGivenOrEstimated) {
  const std::string args = WriteRig({{20.0, 0.0, 0.050}, {20.0, 0.013, -0.030}});
  RunResult r = Run(args + " --time-offset cam1=0.05,cam2=auto --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["slaves"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["slaves"][0]["time_offset_s"].get<double>(), 0.05);
  EXPECT_TRUE(j["slaves"][0]["time_offset_std_s"].is_null());
  const double offset = j["slaves"][1]["time_offset_s"].get<double>();
  const double std = j["slaves"][1]["time_offset_std_s"].get<double>();
  EXPECT_LE(std::abs(offset + 0.030), 4.0 * std) << offset;
  r = Run(args + " --time-offset roof=0.01");
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("--time-offset: 'roof' is not a slave camera"));
  r = Run(args + " --time-offset cam1=soon");
  EXPECT_EQ(r.exit_code, 2) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("cam1: expected auto or a number of seconds, got 'soon'"));
}

// With --config, estimator.time_offset of the rig config gives the offsets; --time-offset
// overrides it; a slave that is not in the config is an error naming it.
TEST_F(SolveTimeOffsetTest, RigConfigTimeOffsetIsReadAndTheFlagOverridesIt) {
  const std::string args = WriteRig({{20.0, 0.0, 0.050}, {20.0, 0.013, -0.030}});
  const std::string rig =
      "rig: {master: master}\ncameras:\n  - name: master\n  - name: cam1\n"
      "  - name: cam2\n";
  std::ofstream(Path("rig.yaml")) << (rig + "estimator: {time_offset: {cam1: 0.05}}\n");
  RunResult r = Run(args + " --config " + Quote(Path("rig.yaml")) + " --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["slaves"].size(), 2u);
  EXPECT_DOUBLE_EQ(j["slaves"][0]["time_offset_s"].get<double>(), 0.05);
  EXPECT_TRUE(j["slaves"][0]["time_offset_std_s"].is_null());
  // cam2 not named in the config's map: estimated.
  const double offset = j["slaves"][1]["time_offset_s"].get<double>();
  const double std = j["slaves"][1]["time_offset_std_s"].get<double>();
  EXPECT_LE(std::abs(offset + 0.030), kSigmas * std) << offset;
  EXPECT_THAT(r.err, HasSubstr("time offsets from"));

  // The flag overrides the config (0.02 s is wrong for both: the timing check says so, exit 3).
  r = Run(args + " --config " + Quote(Path("rig.yaml")) + " --time-offset 0.02 --json");
  ASSERT_EQ(r.exit_code, 3) << Explain(r);
  EXPECT_THAT(r.err, ContainsRegex("timing: the data prefer a time offset of -(29\\.9|30\\.0)"));
  j = nlohmann::json::parse(r.out);
  EXPECT_DOUBLE_EQ(j["slaves"][0]["time_offset_s"].get<double>(), 0.02);
  EXPECT_DOUBLE_EQ(j["slaves"][1]["time_offset_s"].get<double>(), 0.02);

  // A config without time_offset: synchronised stamps (offset 0), as without --config.
  std::ofstream(Path("plain.yaml")) << (rig);
  r = Run(args + " --config " + Quote(Path("plain.yaml")) + " --json");
  ASSERT_EQ(r.exit_code, 3) << Explain(r);  // cam1 runs a frame (50 ms) off: timing check
  EXPECT_THAT(r.err, HasSubstr("for 'cam1'"));
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(r.out)["slaves"][0]["time_offset_s"].get<double>(), 0.0);

  // A slave the config does not have; a broken config.
  std::ofstream(Path("other.yaml"))
      << ("rig: {master: master}\ncameras:\n  - name: master\n  - name: cam1\n");
  r = Run(args + " --config " + Quote(Path("other.yaml")));
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("slave 'cam2' is not a slave camera of the rig config"));
  std::ofstream(Path("bad.yaml")) << (rig + "estimator: {time_offset: soon}\n");
  r = Run(args + " --config " + Quote(Path("bad.yaml")));
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("estimator.time_offset: must be auto or a number of seconds"));
  r = Run("solve --help");
  EXPECT_THAT(r.out, HasSubstr("overrides the config"));
}

TEST_F(SolveTimeOffsetTest, BadInputIsAClearError) {
  const std::string args = WriteRig({{20.0, 0.0, 0.0}, {20.0, 0.0, 0.0}});
  RunResult r = Run(args + " --time-offset soon");
  EXPECT_EQ(r.exit_code, 2) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("expected auto or a number of seconds, got 'soon'"));
  // A slave with too few poses.
  TimedTrajectory few = rig_.slaves[1];
  few.t_ns.resize(4), few.poses.resize(4), few.segment.resize(4);
  ASSERT_TRUE(io::WriteTrajectoryTum(Path("cam2.txt"), few).ok());
  r = Run(args + " --time-offset auto");
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: time offset of 'cam2': camera 'cam2' has 4 poses"));
  // A search window without enough overlap (the slave's clock 100 s ahead).
  TimedTrajectory late = rig_.slaves[1];
  for (int64_t& t : late.t_ns) t += 100'000'000'000;
  ASSERT_TRUE(io::WriteTrajectoryTum(Path("cam2.txt"), late).ok());
  r = Run(args + " --time-offset auto --time-offset-window 0.2");
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("time offset of 'cam2': master and slave overlap by less than"));
}

}  // namespace
}  // namespace rigcal
