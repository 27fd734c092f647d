// SPDX-License-Identifier: Apache-2.0
// One truth comparison for every command (issue 37 §3): the same run's poses and truth give
// the same master unit and the same true scales through `run --eval` and `solve --truth DIR`,
// and a truth of mountings alone gives no scale error at all (the slaves' units are unknown).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/command_test.h"

namespace rigcal {
namespace {

using cli_test::Quote;
using cli_test::RunResult;
using ::testing::HasSubstr;

class TruthComparisonTest : public cli_test::CommandTest {};

nlohmann::json Json(const RunResult& r) {
  return nlohmann::json::parse(r.out, nullptr, /*allow_exceptions=*/false);
}

TEST_F(TruthComparisonTest, RunAndSolveAlignTheSameUnits) {
  const std::string config = std::string(RIGCAL_SOURCE_DIR) + "/config/sim_thesis_virtual.yaml";
  const RunResult run = Run("run --config " + Quote(config) + " --fast --eval --json -q" +
                            " --poses-out " + Quote(Path("poses")) + " --truth-out " +
                            Quote(Path("truth")) + " -o " + Quote(Path("run.yaml")));
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json r = Json(run);
  ASSERT_TRUE(r.contains("truth_alignment")) << run.out;
  const double run_unit = r["truth_alignment"]["metres_per_master_unit"].get<double>();
  EXPECT_THAT(r["truth_alignment"]["message"].get<std::string>(), HasSubstr("per master segment"));
  ASSERT_TRUE(r.contains("provenance")) << run.out;

  // solve on the same poses with the truth directory: the same per-segment alignment.
  const RunResult solve =
      Run("solve --master " + Quote(Path("poses/cam0.txt")) + " --slave " +
          Quote(Path("poses/cam1.txt")) + " --truth " + Quote(Path("truth")) + " --json -q");
  ASSERT_EQ(solve.exit_code, 0) << solve.err;
  const nlohmann::json s = Json(solve);
  ASSERT_TRUE(s.contains("truth_alignment")) << solve.out;
  const double solve_unit = s["truth_alignment"]["metres_per_master_unit"].get<double>();
  // The truth's TUM stamps and positions are printed with 9 decimals.
  EXPECT_NEAR(solve_unit, run_unit, 1e-6 * run_unit);
  // Both scored scales against the same segment units: finite scale errors, and small.
  EXPECT_LT(s["slaves"][0]["errors"]["scale_pct"].get<double>(), 2.0) << solve.out;
  EXPECT_LT(r["slaves"][0]["errors"]["scale_pct"].get<double>(), 2.0) << run.out;

  // The mountings alone (truth.yaml): the unit fitted from C, no scale error given.
  const RunResult mountings =
      Run("solve --master " + Quote(Path("poses/cam0.txt")) + " --slave " +
          Quote(Path("poses/cam1.txt")) + " --truth " + Quote(Path("truth/truth.yaml")) +
          " --truth-unit metric --json -q");
  ASSERT_EQ(mountings.exit_code, 0) << mountings.err;
  const nlohmann::json m = Json(mountings);
  EXPECT_TRUE(m["slaves"][0]["errors"]["scale_pct"].is_null()) << mountings.out;
  EXPECT_THAT(m["truth_alignment"]["message"].get<std::string>(), HasSubstr("no scale errors"));

  // report --truth on the run's result: no made-up scale error either.
  const RunResult report = Run("report " + Quote(Path("run.yaml")) + " --truth " +
                               Quote(Path("truth/truth.yaml")) + " -o " + Quote(Path("r.html")));
  ASSERT_EQ(report.exit_code, 0) << report.err;
  EXPECT_THAT(cli_test::Slurp(Path("r.html")), HasSubstr("unknown slave unit"));
}

}  // namespace
}  // namespace rigcal
