// SPDX-License-Identifier: Apache-2.0
// CameraPose::quality reaches the recursive estimator (calib/src/motions/pose_quality_gate.h):
// sets whose master or slave pose was tracked far worse than the camera's usual quality are
// neither keyframes nor in the history of the batch refinement, and are counted in the slave's
// online state and message. A clean drive, whatever its qualities' own scatter, gives the
// estimate it gave without them bit for bit; a burst of poorly tracked, noisier poses is
// gated, and the estimate stays within 3 σ of the truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

const std::vector<std::string> kNames = {"front", "left", "back"};

SyntheticDrive Drive() {
  DriveOptions d;
  d.num_frames = 1200;
  d.seed = 3;
  return GenerateDrive(kNames, DemoRig(), d);
}

// How the sets are fed: each pose's quality from `quality(camera, k)`, and the master's pose
// of sets in [burst_from, burst_to) disturbed by Gaussian rotation noise of burst_deg.
struct Feed {
  std::function<double(int camera, size_t k)> quality = [](int, size_t) { return 1.0; };
  size_t burst_from = 0, burst_to = 0;
  double burst_deg = 0.0;
};

RigEstimate EstimateOn(const SyntheticDrive& drive, const Feed& feed) {
  RigEstimator estimator(kNames, RigEstimatorOptions{});
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const RigRecording& rec = drive.recording;
  for (size_t k = 0; k < rec.size(); ++k) {
    std::vector<std::optional<CameraPose>> set = rec.SetAt(k);
    for (size_t c = 0; c < set.size(); ++c) set[c]->quality = feed.quality(static_cast<int>(c), k);
    if (k >= feed.burst_from && k < feed.burst_to) {
      const Eigen::Vector3d v(gauss(rng), gauss(rng), gauss(rng));
      set[0]->pose.q = set[0]->pose.q * AxisAngle(v.normalized(), feed.burst_deg * kRadPerDeg *
                                                                      v.norm() / std::sqrt(3.0));
    }
    estimator.AddSet(rec.t_ns[k], set);
  }
  return estimator.Estimate();
}

TEST(PoseQuality, CleanDriveIsUnchangedWhateverItsQualities) {
  const SyntheticDrive drive = Drive();
  const RigEstimate ones = EstimateOn(drive, Feed{});
  // Qualities as a VO reports them on clean frames: around 0.9, varying by a few hundredths.
  Feed scattered;
  scattered.quality = [](int camera, size_t k) {
    return 0.9 + 0.03 * std::sin(0.37 * static_cast<double>(k) + camera);
  };
  const RigEstimate varied = EstimateOn(drive, scattered);
  ASSERT_EQ(ones.rig.slaves.size(), varied.rig.slaves.size());
  for (size_t i = 0; i < ones.rig.slaves.size(); ++i) {
    const SlaveCalibration& a = ones.rig.slaves[i];
    const SlaveCalibration& b = varied.rig.slaves[i];
    EXPECT_EQ(varied.online[i].poorly_tracked, 0) << a.name;
    EXPECT_EQ(a.estimate.q.coeffs(), b.estimate.q.coeffs()) << a.name;
    EXPECT_EQ(a.estimate.C, b.estimate.C) << a.name;
    EXPECT_EQ(a.estimate.scale, b.estimate.scale) << a.name;
    EXPECT_EQ(a.message, b.message) << a.name;
  }
}

TEST(PoseQuality, PoorlyTrackedBurstIsGatedAndCounted) {
  const SyntheticDrive drive = Drive();
  // 3 s of a 60-s drive whose master frames are blurred: fewer inliers, a pose 1° off.
  Feed burst;
  burst.burst_from = 600;
  burst.burst_to = 660;
  burst.burst_deg = 1.0;
  burst.quality = [&](int camera, size_t k) {
    const bool blurred = camera == 0 && k >= burst.burst_from && k < burst.burst_to;
    return (blurred ? 0.25 : 0.9) + 0.03 * std::sin(0.37 * static_cast<double>(k) + camera);
  };
  Feed unrated = burst;  // the same poses without a quality
  unrated.quality = [](int, size_t) { return 1.0; };
  const RigEstimate gated = EstimateOn(drive, burst);
  const RigEstimate ungated = EstimateOn(drive, unrated);
  for (size_t i = 0; i < gated.rig.slaves.size(); ++i) {
    const SlaveCalibration& g = gated.rig.slaves[i];
    const SlaveCalibration& u = ungated.rig.slaves[i];
    const double g_err = AngleBetween(g.estimate.q, drive.truth[i].q) * kDegPerRad;
    const double u_err = AngleBetween(u.estimate.q, drive.truth[i].q) * kDegPerRad;
    std::printf(
        "%s: gated %d sets; rotation error %.4f deg (sigma %.4f) gated, %.4f deg (sigma "
        "%.4f) without the quality\n  %s\n",
        g.name.c_str(), gated.online[i].poorly_tracked, g_err, g.rot_std_deg, u_err, u.rot_std_deg,
        g.message.c_str());
    // Every burst set is gated, unless the glitch gate (which runs first) dropped it already.
    const int glitched = g.glitches.dropped();
    EXPECT_GE(gated.online[i].poorly_tracked, 60 - glitched) << g.name;
    EXPECT_LE(gated.online[i].poorly_tracked, 60) << g.name;
    EXPECT_EQ(ungated.online[i].poorly_tracked, 0) << g.name;
    EXPECT_NE(g.message.find(std::to_string(gated.online[i].poorly_tracked) +
                             " sets of poorly tracked poses not used"),
              std::string::npos)
        << g.message;
    ASSERT_TRUE(g.usable()) << g.message;
    EXPECT_LE(g_err, 3.0 * g.rot_std_deg) << g.name;
  }
}

}  // namespace
}  // namespace rigcal
