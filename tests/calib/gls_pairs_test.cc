// SPDX-License-Identifier: Apache-2.0
// The gls pair policy (PairOptions::Policy::kGls, calib/src/batch/batch_gls.h): auto's result refined
// by generalised least squares on every consecutive motion, whitened by the fitted pose noise.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

SyntheticDrive WhiteNoiseDrive(uint64_t seed) {
  DriveOptions opt;
  opt.num_frames = 800;
  opt.frame_rate_hz = 20.0;
  opt.rotation_noise_deg = 0.1;
  opt.position_noise = 0.003;
  opt.seed = seed;
  return GenerateDrive({"m", "s1", "s2"}, DemoRig(), opt);
}

TEST(GlsPairs, NamedInTheResult) {
  const SyntheticDrive d = WhiteNoiseDrive(1);
  CalibrationOptions options;
  options.pairs.policy = PairOptions::Policy::kGls;
  options.pairs.gls_keep_more_certain = false;
  const RigCalibration r = CalibrateRig(d.recording, options);
  ASSERT_EQ(r.slaves.size(), 2u);
  for (const SlaveCalibration& s : r.slaves) {
    ASSERT_TRUE(s.solved()) << s.message;
    EXPECT_EQ(s.pairs, "gls") << s.message;
    EXPECT_NE(s.message.find("generalised least squares"), std::string::npos) << s.message;
    EXPECT_TRUE(std::isfinite(s.rot_std_deg));
    EXPECT_TRUE(s.pos_std.allFinite());
  }
}

// Normalised errors of results against the truth: E|ΔC|² = tr Cov(C) = |σ_C|², the rotation
// angle² at most 3 σ_max² in expectation.
struct Honesty {
  double pos_z = 0.0;
  double rot_z = 0.0;
  int n = 0;
  void Add(const SlaveCalibration& s, const Similarity& truth) {
    const CalibrationError e = CompareToTruth(s.estimate, truth);
    pos_z += (s.estimate.C - truth.C).squaredNorm() / s.pos_std.squaredNorm();
    rot_z += e.rot_deg * e.rot_deg / (3.0 * s.rot_std_deg * s.rot_std_deg);
    ++n;
  }
  // Means within ~3 standard errors of 1 (16 results of χ²₃/3 terms: ~0.2).
  void ExpectHonest() const {
    std::printf("mean |dC|^2/|sigma_C|^2 %.2f, angle^2/(3 sigma_max^2) %.2f over %d results\n",
                pos_z / n, rot_z / n, n);
    EXPECT_GT(pos_z / n, 0.4);
    EXPECT_LT(pos_z / n, 1.8);
    EXPECT_LT(rot_z / n, 1.8);
    EXPECT_GT(rot_z / n, 0.1);
  }
};

// On white pose noise the σ of the whitened system matches the spread of the errors over
// draws: E|ΔC|² = tr Cov(C) = |σ_C|², so the mean of |ΔC|²/|σ_C|² over 2 slaves x 8 draws is
// 1 with a standard error of ~0.2 (each term ~ χ²₃/3); the rotation angle² is at most
// 3 σ_max² in expectation. Bounds at ~3 standard errors.
TEST(GlsPairs, SigmaMatchesTheSpreadOnWhiteNoise) {
  Honesty honesty;
  double rot_gls = 0.0, rot_auto = 0.0, pos_gls = 0.0, pos_auto = 0.0;
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const SyntheticDrive d = WhiteNoiseDrive(seed);
    CalibrationOptions options;
    options.pairs.policy = PairOptions::Policy::kGls;
    options.pairs.gls_keep_more_certain = false;  // the GLS estimate and σ themselves
    const RigCalibration r = CalibrateRig(d.recording, options);
    options.pairs.policy = PairOptions::Policy::kAuto;
    const RigCalibration a = CalibrateRig(d.recording, options);
    for (size_t i = 0; i < d.truth.size(); ++i) {
      rot_gls += std::pow(CompareToTruth(r.slaves[i].estimate, d.truth[i]).rot_deg, 2);
      rot_auto += std::pow(CompareToTruth(a.slaves[i].estimate, d.truth[i]).rot_deg, 2);
      pos_gls += (r.slaves[i].estimate.C - d.truth[i].C).squaredNorm();
      pos_auto += (a.slaves[i].estimate.C - d.truth[i].C).squaredNorm();
    }
    for (size_t i = 0; i < d.truth.size(); ++i) {
      const SlaveCalibration& s = r.slaves[i];
      ASSERT_TRUE(s.solved()) << s.message;
      ASSERT_EQ(s.pairs, "gls") << s.message;
      honesty.Add(s, d.truth[i]);
    }
  }
  const int n = honesty.n;
  std::printf("RMS error gls / auto: rotation %.4f / %.4f deg, C %.5f / %.5f\n",
              std::sqrt(rot_gls / n), std::sqrt(rot_auto / n), std::sqrt(pos_gls / n),
              std::sqrt(pos_auto / n));
  honesty.ExpectHonest();
}

// On white pose noise the span that determines the rotation best is often not the one that
// determines C best (the rotation gains from long spans, C's lever arm less): the mixture takes
// each part from its span, the rotation carried over with its covariance into C's solve. Its σ
// must stay honest; gls_mixture = false turns
// it off.
TEST(GlsPairs, MixtureOfSpansIsHonest) {
  Honesty honesty;
  int mixed = 0, mixed_when_off = 0;
  const std::string mark = "with that rotation carried over";
  for (uint64_t seed = 1; seed <= 8; ++seed) {
    const SyntheticDrive d = WhiteNoiseDrive(seed);
    CalibrationOptions options;
    const RigCalibration r = CalibrateRig(d.recording, options);
    options.pairs.gls_mixture = false;
    const RigCalibration off = CalibrateRig(d.recording, options);
    for (size_t i = 0; i < d.truth.size(); ++i) {
      const SlaveCalibration& s = r.slaves[i];
      ASSERT_TRUE(s.solved()) << s.message;
      if (s.message.find(mark) != std::string::npos) ++mixed;
      if (off.slaves[i].message.find(mark) != std::string::npos) ++mixed_when_off;
      honesty.Add(s, d.truth[i]);
    }
  }
  std::printf("%d of %d results mixed\n", mixed, honesty.n);
  EXPECT_GT(mixed, 0);
  EXPECT_EQ(mixed_when_off, 0);
  honesty.ExpectHonest();
}

}  // namespace
}  // namespace rigcal
