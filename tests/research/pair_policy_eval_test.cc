// Issue requirement on the whole pair-policy evaluation set (`rigcal experiment pairs`): the
// default pair policy within 1.5x of the best fixed span in rotation and in position on every
// recording (the table and the 1.2x count are printed). Label eval: minutes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "rigcal/research/pair_evaluation.h"
#include "support/skip.h"

namespace rigcal {
namespace {

TEST(PairPolicyEval, DefaultWithinOneAndAHalfOfTheBestFixedSpan) {
  const std::string dir = std::string(RIGCAL_SHARED_DATA_DIR) + "/trajectories";
  std::vector<std::string> notes;
  const std::vector<PairScenario> scenarios = PairScenarios(dir, &notes);
  for (const auto& note : notes) std::cout << "note: " << note << "\n";
  if (!notes.empty() && std::getenv("CI") != nullptr && std::string(std::getenv("CI")) == "true") {
    FAIL() << "real trajectories missing under CI: " << notes.front();
  }
  PairEvaluationOptions options;
  options.repeats = 6;
  options.online = false;
  const auto results = RunPairEvaluation(scenarios, options);
  std::cout << FormatPairTable(results);
  for (const auto& r : results) {
    const PolicyFigures* a = r.Find("auto");
    ASSERT_NE(a, nullptr);
    EXPECT_EQ(a->failed, 0) << r.name;
    ASSERT_GE(r.best_rot, 0) << r.name;
    EXPECT_LE(a->rot_rms_deg, 1.5 * r.policies[r.best_rot].rot_rms_deg) << r.name;
    if (r.best_pos >= 0) EXPECT_LE(a->pos_rms, 1.5 * r.policies[r.best_pos].pos_rms) << r.name;
  }
  if (!notes.empty()) RIGCAL_SKIP_MISSING() << "real trajectories left out: " << notes.front();
}

}  // namespace
}  // namespace rigcal
