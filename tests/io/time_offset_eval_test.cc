// SPDX-License-Identifier: Apache-2.0
// Figures for free-running cameras (label eval): the estimated clock offset and its σ against
// the truth for offsets from -100 to +100 ms and phases within a frame, the extrinsic errors
// of the free-running rig against the same rig synchronised, and the cost of interpolating a
// slave pose at a master instant.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "../calib/free_running_rig.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/io/time_offset.h"
#include "rigcal/io/trajectory_interpolation.h"

namespace rigcal::io {
namespace {

using free_running::CameraClock;

constexpr double kDurationS = 30.0;

RigCalibration Solve(const free_running::FreeRunningRig& rig,
                     std::vector<TimeOffsetEstimate>* out) {
  const auto matched =
      MatchWithTimeOffsets(rig.master, rig.slaves, std::nullopt, 5'000'000, CalibrationOptions{});
  EXPECT_TRUE(matched) << matched.error();
  if (!matched) return {};
  *out = matched->offsets;
  return CalibrateRig(matched->recording, CalibrationOptions{});
}

TEST(TimeOffsetEval, OffsetAndExtrinsicErrorsAgainstTheTruth) {
  const std::vector<Similarity> rigs = {DemoRig()[0]};
  DriveOptions options;
  options.seed = 11;
  std::vector<TimeOffsetEstimate> offsets;
  const RigCalibration sync =
      Solve(free_running::MakeFreeRunningRig({}, {{}}, rigs, kDurationS, options), &offsets);
  ASSERT_EQ(sync.slaves.size(), 1u);
  const CalibrationError sync_error = CompareToTruth(sync.slaves[0].estimate, rigs[0]);
  std::printf("slave 20 Hz, master 20 Hz, %.0f s, rotation noise %.2f deg, position %.3f\n",
              kDurationS, options.rotation_noise_deg, options.position_noise);
  std::printf(
      "synchronised: offset %+.3f ms (std %.3f ms), rot err %.4f deg (std %.4f), "
      "C err %.5f (std %.5f)\n",
      offsets[0].offset_s * 1e3, offsets[0].std_s * 1e3, sync_error.rot_deg,
      sync.slaves[0].rot_std_deg, sync_error.trans_err, sync.slaves[0].pos_std.norm());
  std::printf("%9s %9s %11s %10s %8s %12s %12s\n", "truth ms", "phase", "error ms", "std ms",
              "|e|/std", "rot err deg", "C err");
  double sum_z2 = 0.0;
  int n = 0;
  for (const double offset_ms : {-100.0, -60.0, -20.0, 0.0, 20.0, 60.0, 100.0}) {
    for (const double phase : {0.0, 0.3, 0.7}) {
      const CameraClock clock{20.0, phase / 20.0, offset_ms * 1e-3};
      ++options.seed;  // independent noise per case
      const RigCalibration result =
          Solve(free_running::MakeFreeRunningRig({}, {clock}, rigs, kDurationS, options), &offsets);
      ASSERT_EQ(result.slaves.size(), 1u);
      const CalibrationError e = CompareToTruth(result.slaves[0].estimate, rigs[0]);
      const double error = offsets[0].offset_s - clock.offset_s;
      const double z = std::abs(error) / offsets[0].std_s;
      std::printf("%9.1f %9.2f %+11.4f %10.4f %8.2f %12.4f %12.5f\n", offset_ms, phase, error * 1e3,
                  offsets[0].std_s * 1e3, z, e.rot_deg, e.trans_err);
      EXPECT_LE(z, 5.0) << "offset " << offset_ms << " ms, phase " << phase;
      sum_z2 += z * z;
      ++n;
    }
  }
  std::printf("rms of error/std: %.2f over %d cases (1 when sigma is right)\n",
              std::sqrt(sum_z2 / n), n);
}

// A rig nobody tuned the offset estimate on: three slaves at 15, 25 and 30 Hz with random
// phases, offsets 0, +37 and -21 ms, a 20 Hz master, 40 s, over many draws. The offsets must be
// unbiased (the mean normalised error near 0) and their σ honest (normalised errors ~N(0,1));
// the extrinsics' and scales' σ include the offset's (io::PropagateTimeOffsetSigma).
TEST(TimeOffsetEval, HeldOutThreeSlaveRigIsUnbiasedWithHonestSigma) {
  Similarity up;  // looking up, a fifth of the master's unit
  up.q = Eigen::Quaterniond(Eigen::AngleAxisd(-80.0 * kRadPerDeg, Eigen::Vector3d::UnitX()));
  up.C = Eigen::Vector3d(0.4, -0.6, 0.3);
  up.scale = 0.2;
  const std::vector<Similarity> rigs = {DemoRig()[0], DemoRig()[1], up};
  const double offsets_s[] = {0.0, 0.037, -0.021};
  const double rates_hz[] = {15.0, 25.0, 30.0};
  constexpr int kDraws = 12;
  std::vector<double> z_offset[3], z_rot, z_pos, z_scale;
  std::printf("%5s %6s %10s %9s %7s\n", "draw", "slave", "error ms", "std ms", "z");
  for (int draw = 0; draw < kDraws; ++draw) {
    DriveOptions options;
    options.seed = 500 + 7 * draw;
    std::vector<CameraClock> clocks;
    for (int i = 0; i < 3; ++i) {
      const double phase = std::fmod(0.37 * (draw + 1) * (i + 2), 1.0);
      clocks.push_back({rates_hz[i], phase / rates_hz[i], offsets_s[i]});
    }
    const auto rig = free_running::MakeFreeRunningRig({}, clocks, rigs, 40.0, options);
    const auto matched =
        MatchWithTimeOffsets(rig.master, rig.slaves, std::nullopt, 5'000'000, CalibrationOptions{});
    ASSERT_TRUE(matched) << matched.error();
    RigCalibration result = CalibrateRig(matched->recording, CalibrationOptions{});
    ASSERT_TRUE(PropagateTimeOffsetSigma(rig.master, rig.slaves, *matched, 5'000'000,
                                         CalibrationOptions{}, &result)
                    .ok());
    for (int i = 0; i < 3; ++i) {
      const TimeOffsetEstimate& o = matched->offsets[i];
      const double z = (o.offset_s - offsets_s[i]) / o.std_s;
      z_offset[i].push_back(z);
      std::printf("%5d %6d %+10.4f %9.4f %+7.2f\n", draw, i + 1, (o.offset_s - offsets_s[i]) * 1e3,
                  o.std_s * 1e3, z);
      const SlaveCalibration& s = result.slaves[i];
      const CalibrationError e = CompareToTruth(s.estimate, rigs[i]);
      z_rot.push_back(e.rot_deg / s.rot_std_deg);
      z_pos.push_back((s.estimate.C - rigs[i].C).cwiseQuotient(s.pos_std).norm() / std::sqrt(3.0));
      z_scale.push_back((s.estimate.scale - rigs[i].scale) / s.scales[0].std);
    }
  }
  auto mean = [](const std::vector<double>& v) {
    double m = 0.0;
    for (double x : v) m += x;
    return m / static_cast<double>(v.size());
  };
  auto rms = [](const std::vector<double>& v) {
    double m = 0.0;
    for (double x : v) m += x * x;
    return std::sqrt(m / static_cast<double>(v.size()));
  };
  for (int i = 0; i < 3; ++i) {
    const double n = static_cast<double>(z_offset[i].size());
    std::printf("slave %d (%.0f Hz, %+.0f ms): mean z %+.2f (±%.2f for no bias), rms z %.2f\n",
                i + 1, rates_hz[i], offsets_s[i] * 1e3, mean(z_offset[i]), 3.0 / std::sqrt(n),
                rms(z_offset[i]));
    // Unbiased: the mean normalised error within 3 standard errors of 0.
    EXPECT_LT(std::abs(mean(z_offset[i])), 3.0 / std::sqrt(n)) << "slave " << i + 1;
    EXPECT_GT(rms(z_offset[i]), 0.5) << "slave " << i + 1;
    EXPECT_LT(rms(z_offset[i]), 1.6) << "slave " << i + 1;
  }
  // Rotation error / σ: the largest-axis σ against the total angle (χ with 3 dof, rms ≈ 1.7 when
  // σ is the same on every axis); C: per-axis rms; scale: rms.
  std::printf("extrinsics: rms rotation error/σ %.2f, rms C error/σ %.2f, rms scale error/σ %.2f\n",
              rms(z_rot), rms(z_pos), rms(z_scale));
  EXPECT_LT(rms(z_rot), 2.0);
  EXPECT_LT(rms(z_pos), 1.6);
  EXPECT_LT(rms(z_scale), 1.6);
}

TEST(TimeOffsetEval, InterpolationCostPerPose) {
  DriveOptions options;
  const auto rig =
      free_running::MakeFreeRunningRig({}, {{30.0, 0.013, 0.02}}, {DemoRig()[0]}, 120.0, options);
  constexpr int kRepeats = 20;
  size_t poses = 0;
  const auto start = std::chrono::steady_clock::now();
  for (int r = 0; r < kRepeats; ++r) {
    poses += ResampleAt(rig.slaves[0], rig.master.t_ns, 20'000'000).size();
  }
  const double ns =
      std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count();
  ASSERT_GT(poses, 0u);
  std::printf(
      "interpolation (cubic, binary search in %zu slave poses): %.0f ns per "
      "pose\n",
      rig.slaves[0].size(), ns / static_cast<double>(poses));
}

}  // namespace
}  // namespace rigcal::io
