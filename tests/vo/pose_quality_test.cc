// SPDX-License-Identifier: Apache-2.0
// CameraPose::quality sees what makes a frame's tracks worse: on the rendered room
// (support/room_sequence.h) a burst of blurred frames and a burst of strong image noise lower
// the quality of their poses well below the clean frames', and the clean frames keep theirs.
// FrameNoiseReference alone: the factor is 1 on usual frames, (usual / σ_f)² on noisier ones,
// and a burst shorter than half its window does not move the usual σ_f.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "../../vo/src/frame_noise_reference.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/vo/monocular_vo.h"
#include "support/ideal_cameras.h"
#include "support/room_sequence.h"

namespace rigcal::vo {
namespace {

constexpr int64_t kFrameNs = 50'000'000;  // 20 Hz
constexpr int kFrames = 160;
constexpr int kBurstBegin = 90;
constexpr int kBurstEnd = 110;

TEST(FrameNoiseReference, UsualFramesKeepFullQualityNoisierOnesLoseItAsOneOverSigmaSquared) {
  FrameNoiseReference reference;
  EXPECT_EQ(reference.Add(0.05), 1.0);  // the first frame has nothing to compare with
  // Usual frames: σ_f within a few percent of 0.05 px.
  for (int k = 0; k < 100; ++k) reference.Add(0.05 * (1.0 + 0.02 * ((k % 5) - 2)));
  const double usual = reference.UsualSigmaPx();
  EXPECT_GT(usual, 0.05);  // the median plus three robust spreads
  EXPECT_LT(usual, 0.05 * 1.2);
  EXPECT_EQ(reference.Add(0.05), 1.0);
  EXPECT_EQ(reference.Add(0.01), 1.0);  // better than usual: no bonus
  // Twice and four times the usual σ_f: (usual / σ_f)².
  EXPECT_NEAR(reference.Add(2.0 * usual), 0.25, 1e-3);
  EXPECT_NEAR(reference.Add(4.0 * usual), 1.0 / 16.0, 1e-3);
  // Not finite or not positive: no measurement, factor 1, the reference unchanged.
  const double before = reference.UsualSigmaPx();
  EXPECT_EQ(reference.Add(0.0), 1.0);
  EXPECT_EQ(reference.Add(std::numeric_limits<double>::quiet_NaN()), 1.0);
  EXPECT_EQ(reference.UsualSigmaPx(), before);
}

TEST(FrameNoiseReference, ABurstShorterThanHalfTheWindowDoesNotBecomeUsual) {
  FrameNoiseReference reference;
  for (int k = 0; k < FrameNoiseReference::kFrames; ++k) {
    reference.Add(0.05 * (1.0 + 0.02 * ((k % 5) - 2)));
  }
  const double usual = reference.UsualSigmaPx();
  const int burst = FrameNoiseReference::kFrames / 2 - 10;
  double last_factor = 1.0;
  for (int k = 0; k < burst; ++k) last_factor = reference.Add(0.15);
  // The median is still a clean frame's; the spread grew with the burst, but the burst's last
  // frame still counts well below half.
  EXPECT_LT(last_factor, 0.5);
  EXPECT_LT(reference.UsualSigmaPx(), 0.15 / std::sqrt(2.0));
  // A scene noisier for good: after a whole window of it, it is the usual.
  for (int k = 0; k < FrameNoiseReference::kFrames; ++k) last_factor = reference.Add(0.15);
  EXPECT_EQ(last_factor, 1.0);
  EXPECT_GT(reference.UsualSigmaPx(), usual);
}

// The room's frames 0 .. kFrames - 1 with frames kBurstBegin .. kBurstEnd - 1 changed by
// `spoil`; the quality of every pose by frame (0 where the VO gave none).
std::vector<double> QualitiesWithBurst(const std::function<cv::Mat(const cv::Mat&, int)>& spoil) {
  static const auto camera = support::PinholeWithFov(752, 480, 60.0);
  static const std::vector<cv::Mat> images = [] {
    std::vector<Pose> poses;
    for (int k = 0; k < kFrames; ++k) poses.push_back(support::RoomPose(k));
    const sim::SimulatedRig rig = support::MakeRoomSequence(camera, poses).value();
    std::vector<cv::Mat> out;
    for (int k = 0; k < kFrames; ++k) out.push_back(rig.RenderFrame(0, k));
    return out;
  }();
  MonocularVo vo(camera, 0, VoOptions{});
  std::vector<double> quality(kFrames, 0.0);
  for (int k = 0; k < kFrames; ++k) {
    const bool burst = k >= kBurstBegin && k < kBurstEnd;
    const VoResult r = vo.Process(k * kFrameNs, burst ? spoil(images[k], k) : images[k]);
    if (r.pose) quality[static_cast<size_t>(k)] = r.pose->quality;
  }
  return quality;
}

// The median quality of the clean frames tracked before the burst, and of the burst's frames:
// the burst's at most half the clean frames' (the pose gate's drop, pose_quality_gate.h),
// every burst frame tracked, and the clean frames before it near 1.
void ExpectBurstSeen(const std::vector<double>& quality) {
  std::vector<double> clean, burst;
  for (int k = 20; k < kBurstBegin; ++k) {
    if (quality[k] > 0.0) clean.push_back(quality[k]);
  }
  for (int k = kBurstBegin; k < kBurstEnd; ++k) {
    EXPECT_GT(quality[k], 0.0) << "frame " << k << " not tracked";
    burst.push_back(quality[k]);
  }
  ASSERT_GE(clean.size(), 40u) << "the VO tracked too few clean frames";
  const double clean_median = MedianAndSigma(clean).median;
  const double burst_median = MedianAndSigma(burst).median;
  std::printf("median quality: clean %.3f, burst %.3f\n", clean_median, burst_median);
  EXPECT_GT(clean_median, 0.9);
  EXPECT_LT(burst_median, 0.5 * clean_median);
}

TEST(PoseQuality, BlurredFramesLoseQuality) {
  // A blur of σ 1.5 px (defocus, or motion blur across the frame period): the tracks' corners
  // are softer and their positions noisier.
  ExpectBurstSeen(QualitiesWithBurst([](const cv::Mat& image, int) {
    cv::Mat blurred;
    cv::GaussianBlur(image, blurred, cv::Size(0, 0), 1.5);
    return blurred;
  }));
}

TEST(PoseQuality, NoisyFramesLoseQuality) {
  // Gain noise of σ 12 grey levels (a dark scene at high gain) on top of the rendered 1.
  ExpectBurstSeen(QualitiesWithBurst([](const cv::Mat& image, int k) {
    cv::Mat noise(image.size(), CV_16SC1);
    cv::RNG rng(static_cast<uint64_t>(k) + 1);
    rng.fill(noise, cv::RNG::NORMAL, 0.0, 12.0);
    cv::Mat noisy;
    cv::add(image, noise, noisy, cv::noArray(), CV_8UC1);
    return noisy;
  }));
}

}  // namespace
}  // namespace rigcal::vo
