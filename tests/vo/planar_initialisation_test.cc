// SPDX-License-Identifier: Apache-2.0
// The planar initialisation's pieces: the homography of two views of a plane from bearings, its
// decomposition into the true motion, and the choice between a homography and an essential
// matrix by GRIC (a plane or no translation: homography; depth varying: essential matrix).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <vector>

#include "../../vo/src/homography.h"
#include "../../vo/src/relative_pose.h"
#include "../../vo/src/two_view_model_selection.h"

namespace rigcal::vo {
namespace {

constexpr int kPoints = 200;
constexpr double kHalfFieldRad = 0.5;  // points within about ±29 degrees of the optical axis

struct TwoViews {
  RelativePose truth;  // view 2 in view 1
  Eigen::Vector3d normal_in_2 = Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> f1, f2;
};

// A bearing perturbed by an isotropic angular error of `sigma_rad` per axis.
Eigen::Vector3d Perturb(const Eigen::Vector3d& f, double sigma_rad, std::mt19937* rng) {
  std::normal_distribution<double> gauss(0.0, sigma_rad);
  const Eigen::Vector3d a = f.unitOrthogonal();
  const Eigen::Vector3d b = f.cross(a);
  return (f + gauss(*rng) * a + gauss(*rng) * b).normalized();
}

// Points seen by view 2 in directions within the field, at depths on the plane
// n . p = 1 (relief 0) or spread by ±relief around it; view 2 is at C (its baseline over the
// plane's distance) and turned by 3 degrees from view 1.
TwoViews MakeViews(const Eigen::Vector3d& C, double relief, double sigma_rad, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> field(-kHalfFieldRad, kHalfFieldRad);
  std::uniform_real_distribution<double> depth_factor(1.0 - relief, 1.0 + relief);
  TwoViews v;
  v.truth.R_1_from_2 =
      Eigen::AngleAxisd(3.0 * M_PI / 180.0, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())
          .toRotationMatrix();
  v.truth.C2_in_1 = C;
  v.normal_in_2 = Eigen::Vector3d(0.1, -0.3, 1.0).normalized();
  for (int i = 0; i < kPoints; ++i) {
    const Eigen::Vector3d f2 =
        Eigen::Vector3d(std::tan(field(rng)), std::tan(field(rng)), 1.0).normalized();
    const double depth = depth_factor(rng) / v.normal_in_2.dot(f2);  // on the plane n . p = 1
    const Eigen::Vector3d p1 = v.truth.R_1_from_2 * (depth * f2) + C;
    v.f1.push_back(Perturb(p1.normalized(), sigma_rad, &rng));
    v.f2.push_back(Perturb(f2, sigma_rad, &rng));
  }
  return v;
}

double RotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

// Noise-free views of a plane: every point is an inlier and one decomposition is the true
// motion up to rounding.
TEST(Homography, ExactPlaneGivesTheTrueMotion) {
  const Eigen::Vector3d C(0.15, -0.05, 0.1);
  const TwoViews v = MakeViews(C, 0.0, 0.0, 1);
  HomographyRansacOptions options;
  options.max_transfer_angle_rad = 1e-6;
  const HomographyRansacResult h = EstimateHomography(v.f1, v.f2, options);
  ASSERT_TRUE(h.success);
  EXPECT_EQ(h.num_inliers, kPoints);
  bool found = false;
  for (const PlanarMotion& m : DecomposeHomography(h.H_1_from_2)) {
    if (RotationAngle(m.pose.R_1_from_2, v.truth.R_1_from_2) < 1e-6 &&
        (m.pose.C2_in_1 - C.normalized()).norm() < 1e-6) {
      found = true;
      EXPECT_NEAR(m.baseline_over_distance, C.norm(), 1e-6);  // the plane is at distance 1
      EXPECT_LT((m.normal_in_2 - v.normal_in_2).norm(), 1e-6);
    }
  }
  EXPECT_TRUE(found);
}

// Noisy views: the inliers within 3.03 σ √2 (99 % of the two views' transfer error) are nearly
// all points, and the transfer errors of the fit measure the noise: their RMS is about √2 σ per
// axis (the error of both views), i.e. 2 σ as a 2-D magnitude, within the sampling error.
TEST(Homography, NoisyPlaneKeepsTheInliersWithinTheGate) {
  constexpr double kSigma = 1e-3;
  const TwoViews v = MakeViews(Eigen::Vector3d(0.15, -0.05, 0.1), 0.0, kSigma, 2);
  HomographyRansacOptions options;
  options.max_transfer_angle_rad = 3.03 * std::sqrt(2.0) * kSigma;
  const HomographyRansacResult h = EstimateHomography(v.f1, v.f2, options);
  ASSERT_TRUE(h.success);
  // 1 % of a 2-D Gaussian lies beyond 3.03 σ; the transfer angle is the larger of two: ~2 %.
  EXPECT_GE(h.num_inliers, 0.95 * kPoints);
  double sum2 = 0.0;
  for (int i = 0; i < kPoints; ++i) {
    const double a = (h.H_1_from_2 * v.f2[i]).normalized().cross(v.f1[i]).norm();
    sum2 += a * a;
  }
  const double rms = std::sqrt(sum2 / kPoints);
  EXPECT_NEAR(rms, 2.0 * kSigma, 0.25 * 2.0 * kSigma);  // relative sampling error ~1/sqrt(n)
}

// GRIC's choice from the true essential matrix's and the fitted homography's errors.
TwoViewModel Choose(const TwoViews& v, double sigma_rad) {
  HomographyRansacOptions options;
  options.max_transfer_angle_rad = 3.03 * std::sqrt(2.0) * sigma_rad;
  const HomographyRansacResult h = EstimateHomography(v.f1, v.f2, options);
  EXPECT_TRUE(h.success);
  const Eigen::Matrix3d e = EssentialFromPose(v.truth);
  const Eigen::Matrix3d h_inverse = h.H_1_from_2.inverse();
  std::vector<double> epipolar, transfer;
  for (size_t i = 0; i < v.f1.size(); ++i) {
    epipolar.push_back(EpipolarAngle(e, v.f1[i], v.f2[i]));
    transfer.push_back(HomographyTransferAngle(h.H_1_from_2, h_inverse, v.f1[i], v.f2[i]));
  }
  return ChooseTwoViewModel(epipolar, transfer, sigma_rad).model;
}

TEST(TwoViewModelSelection, PlaneOrNoTranslationIsAHomographyDepthIsAnEssentialMatrix) {
  constexpr double kSigma = 1e-3;
  const Eigen::Vector3d C(0.15, -0.05, 0.1);
  // A plane: both relations fit, the homography with fewer dimensions.
  EXPECT_EQ(Choose(MakeViews(C, 0.0, kSigma, 3), kSigma), TwoViewModel::kHomography);
  // ±30 % relief: parallax off the plane of up to 0.3 * 0.18 rad, far beyond the noise.
  EXPECT_EQ(Choose(MakeViews(C, 0.3, kSigma, 4), kSigma), TwoViewModel::kEssential);
  // A translation too small for its parallax (|C| * relief ~ 3e-5 rad) to show in the noise.
  EXPECT_EQ(Choose(MakeViews(1e-4 * C.normalized(), 0.3, kSigma, 5), kSigma),
            TwoViewModel::kHomography);
}

// GRIC itself: the penalties of the dimensions and parameters, and the cap of a bad fit.
TEST(TwoViewModelSelection, GricPenaltiesAndCap) {
  const std::vector<double> perfect(100, 0.0);
  // ln(4) d n + ln(4 n) k
  EXPECT_NEAR(Gric(perfect, 3, 5), std::log(4.0) * 300 + std::log(400.0) * 5, 1e-9);
  EXPECT_NEAR(Gric(perfect, 2, 8), std::log(4.0) * 200 + std::log(400.0) * 8, 1e-9);
  const std::vector<double> outliers(100, 1e6);
  // Every outlier costs λ3 (r - d) = 2 (4 - d).
  EXPECT_NEAR(Gric(outliers, 3, 5) - Gric(perfect, 3, 5), 100 * 2.0, 1e-9);
  EXPECT_NEAR(Gric(outliers, 2, 8) - Gric(perfect, 2, 8), 100 * 4.0, 1e-9);
}

}  // namespace
}  // namespace rigcal::vo
