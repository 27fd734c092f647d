// SPDX-License-Identifier: Apache-2.0
// The auto pair policy (PairOptions::Policy::kAuto, batch_pair_choice.h): per slave, the span
// whose solve reports the most certain estimate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

SyntheticDrive Drive(uint64_t seed, double white_deg, double white_pos, double drift_deg) {
  DriveOptions opt;
  opt.num_frames = 1200;
  opt.frame_rate_hz = 20.0;
  opt.rotation_noise_deg = white_deg;
  opt.position_noise = white_pos;
  opt.drift_deg_per_frame = drift_deg;
  opt.seed = seed;
  return GenerateDrive({"m", "s1", "s2"}, DemoRig(), opt);
}

TEST(AutoPairs, CandidatesAreALadderUpToTheFraction) {
  PairOptions options;
  const std::vector<int> spans = AutoSpanCandidates(1000, options);
  ASSERT_FALSE(spans.empty());
  EXPECT_EQ(spans.front(), 1);
  EXPECT_LE(spans.back(), static_cast<int>(options.auto_max_span_fraction * 1000));
  EXPECT_GT(spans.back() * 1.6, options.auto_max_span_fraction * 1000);  // reaches the end
  for (size_t k = 1; k < spans.size(); ++k) {
    EXPECT_GT(spans[k], spans[k - 1]);
    EXPECT_LE(spans[k], std::max(spans[k - 1] + 1, static_cast<int>(spans[k - 1] * 1.5 + 1)));
  }
  EXPECT_EQ(AutoSpanCandidates(3, options), std::vector<int>{1});
}

// The bound: the default never worse than 1.5x the best fixed span (RMS over draws
// and slaves, rotation and position), here on white pose noise. (Drifting noise is covered
// by tests/research/pair_evaluation_test.cc and `rigcal experiment pairs`.)
TEST(AutoPairs, NotWorseThanTheBestFixedSpan) {
  const std::vector<int> spans = {1, 2, 5, 10, 20, 50, 100};
  for (const bool drifting : {false}) {
    std::vector<double> rot(spans.size() + 1, 0.0), pos(spans.size() + 1, 0.0);
    std::vector<bool> solved(spans.size() + 1, true);  // a span without estimate is no best
    for (uint64_t seed = 1; seed <= 4; ++seed) {
      const SyntheticDrive d =
          drifting ? Drive(seed, 0.005, 0.0005, 0.01) : Drive(seed, 0.1, 0.003, 0.0);
      for (size_t p = 0; p <= spans.size(); ++p) {
        CalibrationOptions options;
        if (p > 0) {
          options.pairs.policy = PairOptions::Policy::kRelative;
          options.pairs.step = spans[p - 1];
        }
        const RigCalibration r = CalibrateRig(d.recording, options);
        for (size_t i = 0; i < d.truth.size(); ++i) {
          if (!r.slaves[i].solved()) {
            ASSERT_GT(p, 0u) << "auto: " << r.slaves[i].message;
            solved[p] = false;
            continue;
          }
          const CalibrationError e = CompareToTruth(r.slaves[i].estimate, d.truth[i]);
          rot[p] += e.rot_deg * e.rot_deg;
          pos[p] += e.trans_err * e.trans_err;
        }
      }
    }
    double best_rot = INFINITY, best_pos = INFINITY;
    for (size_t p = 1; p <= spans.size(); ++p) {
      if (!solved[p]) continue;
      best_rot = std::min(best_rot, rot[p]);
      best_pos = std::min(best_pos, pos[p]);
    }
    ASSERT_TRUE(std::isfinite(best_rot));
    for (size_t p = 0; p <= spans.size(); ++p) {
      std::printf("%s %s: rot %.4g pos %.4g\n", drifting ? "drift" : "white",
                  p == 0 ? "auto" : ("relative:" + std::to_string(spans[p - 1])).c_str(),
                  std::sqrt(rot[p] / 8), std::sqrt(pos[p] / 8));
    }
    EXPECT_LE(std::sqrt(rot[0] / best_rot), 1.5) << (drifting ? "drift" : "white");
    EXPECT_LE(std::sqrt(pos[0] / best_pos), 1.5) << (drifting ? "drift" : "white");
  }
}

}  // namespace
}  // namespace rigcal
