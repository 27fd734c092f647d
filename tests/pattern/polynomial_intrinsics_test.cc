// SPDX-License-Identifier: Apache-2.0
// The polynomial omnidirectional model (scaramuzza) calibrated from simulated views
// (support/omni_views.h): a 200-degree camera (equidistant-like polynomial of high degree,
// f 180 px, centre 12 px off the image centre, affine c = 1.004, d = 0.003) sees a 9x6 board in
// views spread over its field of view, out to 90 degrees and beyond; corners projected by
// rigcal's own model plus Gaussian noise of sigma = 0.1 px.
//
// Tolerances from the math:
// - the fit's RMS is the noise's 2-D RMS, sigma sqrt(2) = 0.141 px (< 0.16 tested);
// - the estimated mapping, compared with the truth at the bearings of the corners after the
//   best rotation between the two camera frames (a small tilt of the frame trades against the
//   centre and is taken up by the extrinsics), is wrong by an amount proportional to sigma:
//   measured 0.5-1.4 sigma RMS over 40 seeds at sigma = 0.01 and 0.1 px, and 0.01 px with no
//   noise (the truth's degree-20 polynomial against the fitted degree <= 7); 2 sigma tested;
// - without the alignment, over bearings up to 80 degrees, what a user projects: within 0.5 px
//   (measured at most 0.38 px over 40 seeds); the centre within 1 px (measured <= 0.22 px);
// - a sign, axis or affine convention error moves any of these by pixels.
// Per-view poses under the true model are scored in pixels (the pose's effect on the corners),
// see the test.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <random>

#include "rigcal/camera/camera_spec.h"
#include "rigcal/pattern/intrinsics.h"
#include "rigcal/pattern/target_poses.h"
#include "support/omni_views.h"

namespace rigcal::pattern {
namespace {

using camera::CameraSpec;
using test_support::AlignedRmsAtCorners;
using test_support::BoardPose;
using test_support::SimulatedOmniViews;
using test_support::WideOmniCamera;
using test_support::WorstProjectionDifference;

constexpr double kSigmaPx = 0.1;

TEST(PolynomialIntrinsics, RecoversTheProjectionOverTheFieldOfView) {
  const CameraSpec truth = WideOmniCamera("omni");
  const pattern::CameraViews views = SimulatedOmniViews(truth, 24, 7, kSigmaPx);
  pattern::IntrinsicsOptions options;
  options.model = CameraSpec::Model::kScaramuzza;
  auto result = pattern::CalibrateIntrinsics(views, options);
  ASSERT_TRUE(result.ok()) << result.error();
  std::cout << pattern::FormatIntrinsics(*result, false);
  const CameraSpec& s = result->spec;
  ASSERT_EQ(s.model, CameraSpec::Model::kScaramuzza);
  ASSERT_TRUE(s.Check().ok()) << s.Check().message();
  EXPECT_LT(result->rms_px, 0.16);
  EXPECT_EQ(result->views_rejected, 0);
  EXPECT_NEAR(s.center[0], truth.center[0], 1.0);
  EXPECT_NEAR(s.center[1], truth.center[1], 1.0);
  const double aligned = AlignedRmsAtCorners(truth, s, views);
  int count = 0;
  const double worst = WorstProjectionDifference(truth, s, 80.0, &count);
  std::printf(
      "mapping at the corners (aligned): RMS %.3f px; %d bearings up to 80 deg: worst %.3f px\n",
      aligned, count, worst);
  EXPECT_LT(aligned, 2.0 * kSigmaPx);
  EXPECT_GT(count, 200);
  EXPECT_LT(worst, 0.5);
}

TEST(PolynomialIntrinsics, NoiselessViewsAreAllKept) {
  // Without noise the residual is the fitted polynomial's departure from the truth's (~0.01 px,
  // larger towards the edge of the field of view): no view is an outlier for it.
  const CameraSpec truth = WideOmniCamera("omni");
  const pattern::CameraViews views = SimulatedOmniViews(truth, 24, 7, /*noise_px=*/0.0);
  pattern::IntrinsicsOptions options;
  options.model = CameraSpec::Model::kScaramuzza;
  auto result = pattern::CalibrateIntrinsics(views, options);
  ASSERT_TRUE(result.ok()) << result.error();
  std::cout << pattern::FormatIntrinsics(*result, true);
  EXPECT_EQ(result->views_rejected, 0);
  EXPECT_LT(result->rms_px, 0.05);
}

TEST(PolynomialIntrinsics, TargetPosesThroughThePolynomialModel) {
  const CameraSpec truth = WideOmniCamera("omni");
  auto model = camera::MakeCameraModel(truth);
  ASSERT_TRUE(model.ok()) << model.error();
  std::vector<BoardPose> poses;
  const pattern::CameraViews views = SimulatedOmniViews(truth, 12, 11, kSigmaPx, &poses);
  auto stats = pattern::EstimateTargetPoses(views, truth, 1.0);
  ASSERT_TRUE(stats.ok()) << stats.error();
  ASSERT_EQ(stats->size(), poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    const pattern::ViewStatistics& v = (*stats)[i];
    ASSERT_TRUE(v.used) << v.file << " rms " << v.rms_px;
    // A view's RMS: sigma sqrt(2 (1 - 6 / 108)) = 0.137 px, spread sigma / sqrt(108) = 0.01.
    EXPECT_LT(v.rms_px, 0.2) << v.file;
    // The corners projected under the estimated and the true pose: 6 pose parameters fitted
    // to 108 coordinates move them by sigma sqrt(6 / 108) = 0.024 px RMS.
    const Eigen::Matrix3d R = v.target_from_cam.q.toRotationMatrix().transpose();
    const Eigen::Vector3d t = -R * v.target_from_cam.C;
    double sum_sq = 0.0;
    for (const Eigen::Vector3d& X : views.views[i].target_points) {
      const auto estimated = (*model)->Project(R * X + t);
      const auto true_pixel = (*model)->Project(poses[i].R * X + poses[i].t);
      ASSERT_TRUE(estimated && true_pixel);
      sum_sq += (*estimated - *true_pixel).squaredNorm();
    }
    const double rms = std::sqrt(sum_sq / static_cast<double>(views.views[i].pixels.size()));
    EXPECT_LT(rms, 0.1) << v.file;
  }
}

TEST(PolynomialIntrinsics, AViewWithWrongCornersIsRejected) {
  const CameraSpec truth = WideOmniCamera("omni");
  pattern::CameraViews views = SimulatedOmniViews(truth, 16, 13, kSigmaPx);
  // Corners of one view shifted by up to 4 px (a wrong detection).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> shift(-4.0, 4.0);
  for (Eigen::Vector2d& p : views.views[5].pixels) {
    const double du = shift(rng);
    const double dv = shift(rng);
    p += Eigen::Vector2d(du, dv);
  }
  pattern::IntrinsicsOptions options;
  options.model = CameraSpec::Model::kScaramuzza;
  auto result = pattern::CalibrateIntrinsics(views, options);
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_TRUE(result->views[5].rejected);
  EXPECT_EQ(result->views_rejected, 1);
  EXPECT_LT(result->rms_px, 0.16);
}

TEST(PolynomialIntrinsics, ATargetOffItsPlaneIsAnError) {
  pattern::CameraViews views = SimulatedOmniViews(WideOmniCamera("omni"), 6, 17, kSigmaPx);
  views.views[2].target_points[4].z() = 0.01;
  pattern::IntrinsicsOptions options;
  options.model = CameraSpec::Model::kScaramuzza;
  auto result = pattern::CalibrateIntrinsics(views, options);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().find("view2"), std::string::npos) << result.error();
  EXPECT_NE(result.error().find("z = 0 plane"), std::string::npos) << result.error();
}

}  // namespace
}  // namespace rigcal::pattern
