// Issue requirement on the whole pair-policy evaluation set (`rigcal experiment pairs`): the
// default pair policy (gls) within 1.5x of the best fixed span in rotation and in position on
// every recording, the online estimate within 1.3x of it (rotation, position, scale); the table
// and the 1.2x counts are printed. 12 draws per recording: with 4 the best of 9 fixed spans is
// often a lucky one. Label eval: ~15 minutes on 2 cores.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "rigcal/research/pair_evaluation.h"
#include "support/skip.h"

namespace rigcal {
namespace {

TEST(PairPolicyEval, DefaultWithinOneAndAHalfOfTheBestFixedSpanOnlineWithinOnePointThree) {
  const std::string dir = std::string(RIGCAL_SHARED_DATA_DIR) + "/trajectories";
  std::vector<std::string> notes;
  const std::vector<PairScenario> scenarios = PairScenarios(dir, &notes);
  for (const auto& note : notes) std::cout << "note: " << note << "\n";
  if (!notes.empty() && std::getenv("CI") != nullptr && std::string(std::getenv("CI")) == "true") {
    FAIL() << "real trajectories missing under CI: " << notes.front();
  }
  PairEvaluationOptions options;
  options.repeats = 12;
  const auto results = RunPairEvaluation(scenarios, options);
  std::cout << FormatPairTable(results);
  for (const auto& r : results) {
    const PolicyFigures* a = r.Find("gls");
    const PolicyFigures* online = r.Find("online");
    ASSERT_NE(a, nullptr);
    ASSERT_NE(online, nullptr);
    EXPECT_EQ(a->failed, 0) << r.name;
    ASSERT_GE(r.best_rot, 0) << r.name;
    EXPECT_LE(a->rot_rms_deg, 1.5 * r.policies[r.best_rot].rot_rms_deg) << r.name;
    if (r.best_pos >= 0) {
      EXPECT_LE(a->pos_rms, 1.5 * r.policies[r.best_pos].pos_rms) << r.name;
    }
    EXPECT_LE(online->rot_rms_deg, 1.3 * a->rot_rms_deg) << r.name;
    EXPECT_LE(online->pos_rms, 1.3 * a->pos_rms) << r.name;
    EXPECT_LE(online->scale_rms_pct, 1.3 * a->scale_rms_pct) << r.name;
  }
  if (!notes.empty()) RIGCAL_SKIP_MISSING() << "real trajectories left out: " << notes.front();
}

}  // namespace
}  // namespace rigcal
