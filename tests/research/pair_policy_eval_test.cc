// SPDX-License-Identifier: Apache-2.0
// Issue requirement on the whole pair-policy evaluation set (`rigcal experiment pairs`): the
// default pair policy (gls) within 1.2x of the best fixed span in rotation and in position on
// every recording, the online estimate within 1.3x of it (rotation, position, scale) with σ as
// honest (RMS normalised errors over the recordings within 10 % of gls's); the table and the
// counts are printed. 12 draws per recording: with 4 the best of 9 fixed spans is often a
// lucky one. Label eval: ~20 minutes on 2 cores (the same figures as `rigcal experiment pairs
// --data ../shared/data/trajectories --repeats 12`).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>

#include "rigcal/research/pair_evaluation.h"
#include "support/skip.h"

namespace rigcal {
namespace {

TEST(PairPolicyEval, DefaultWithinOnePointTwoOfTheBestFixedSpanOnlineWithinOnePointThree) {
  const std::string dir = std::string(RIGCAL_SHARED_DATA_DIR) + "/trajectories";
  std::vector<std::string> notes;
  const std::vector<research::PairScenario> scenarios = research::PairScenarios(dir, &notes);
  for (const auto& note : notes) std::cout << "note: " << note << "\n";
  if (!notes.empty() && std::getenv("CI") != nullptr && std::string(std::getenv("CI")) == "true") {
    FAIL() << "real trajectories missing under CI: " << notes.front();
  }
  research::PairEvaluationOptions options;
  options.repeats = 12;
  const auto results = research::RunPairEvaluation(scenarios, options);
  std::cout << research::FormatPairTable(results);
  double gls_z[2] = {0, 0}, online_z[2] = {0, 0};
  for (const auto& r : results) {
    const research::PolicyFigures* a = r.Find("gls");
    const research::PolicyFigures* online = r.Find("online");
    ASSERT_NE(a, nullptr);
    ASSERT_NE(online, nullptr);
    EXPECT_EQ(a->failed, 0) << r.name;
    ASSERT_GE(r.best_rot, 0) << r.name;
    EXPECT_LE(a->rot_rms_deg, 1.2 * r.policies[r.best_rot].rot_rms_deg) << r.name;
    if (r.best_pos >= 0) {
      EXPECT_LE(a->pos_rms, 1.2 * r.policies[r.best_pos].pos_rms) << r.name;
    }
    EXPECT_LE(online->rot_rms_deg, 1.3 * a->rot_rms_deg) << r.name;
    EXPECT_LE(online->pos_rms, 1.3 * a->pos_rms) << r.name;
    EXPECT_LE(online->scale_rms_pct, 1.3 * a->scale_rms_pct) << r.name;
    const double gz[2] = {a->rot_z_rms, a->pos_z_rms};
    const double oz[2] = {online->rot_z_rms, online->pos_z_rms};
    for (int k = 0; k < 2; ++k) {
      if (std::isfinite(gz[k]) && std::isfinite(oz[k])) {
        gls_z[k] += gz[k] * gz[k];
        online_z[k] += oz[k] * oz[k];
      }
    }
  }
  for (int k = 0; k < 2; ++k) {
    EXPECT_LE(std::sqrt(online_z[k]), 1.1 * std::sqrt(gls_z[k])) << (k == 0 ? "rotation" : "C");
  }
  if (!notes.empty()) RIGCAL_SKIP_MISSING() << "real trajectories left out: " << notes.front();
}

// Issue 36 §5: online within 1.3x of the batch (gls) on rigs nobody tuned for
// (HeldOutPairScenarios: another camera layout, scales 0.1-4, 5-50 Hz, 40-600 s, white and drift
// noise); the table is printed (`rigcal experiment pairs --held-out --data
// ../shared/data/trajectories`).
TEST(PairPolicyEval, HeldOutRigsOnlineWithinOnePointThreeOfTheBatch) {
  const std::string dir = std::string(RIGCAL_SHARED_DATA_DIR) + "/trajectories";
  std::vector<std::string> notes;
  const std::vector<research::PairScenario> scenarios = research::HeldOutPairScenarios(dir, &notes);
  for (const auto& note : notes) std::cout << "note: " << note << "\n";
  research::PairEvaluationOptions options;
  options.repeats = 4;
  options.spans = {};
  const auto results = research::RunPairEvaluation(scenarios, options);
  std::cout << research::FormatPairTable(results);
  for (const auto& r : results) {
    const research::PolicyFigures* batch = r.Find("gls");
    const research::PolicyFigures* online = r.Find("online");
    ASSERT_NE(batch, nullptr);
    ASSERT_NE(online, nullptr);
    EXPECT_EQ(online->failed, 0) << r.name;
    EXPECT_LE(online->rot_rms_deg, 1.3 * batch->rot_rms_deg) << r.name;
    EXPECT_LE(online->pos_rms, 1.3 * batch->pos_rms) << r.name;
    EXPECT_LE(online->scale_rms_pct, 1.3 * batch->scale_rms_pct) << r.name;
  }
}

}  // namespace
}  // namespace rigcal
