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
