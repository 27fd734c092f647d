// SPDX-License-Identifier: Apache-2.0
// Geometry of the VO on unit bearing vectors: 5-point essential matrix, its decomposition and
// RANSAC, triangulation, P3P, PnP RANSAC and motion-only refinement. Synthetic points seen by
// a pinhole-like and by a 186-degree field of view (bearings with z <= 0 included).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "../../vo/src/absolute_pose.h"
#include "../../vo/src/relative_pose.h"
#include "../../vo/src/triangulation.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal::vo {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d RandomRotation(std::mt19937* rng, double max_angle_rad) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3d axis = RandomVector3(n, *rng).normalized();
  return Eigen::AngleAxisd(max_angle_rad * u(*rng), axis).toRotationMatrix();
}

double RotationAngle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle();
}

double VectorAngle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// A point in camera 1's frame seen within `half_fov_rad` of camera 1's optical axis, at a
// distance in [2, 8].
Eigen::Vector3d RandomPoint(std::mt19937* rng, double half_fov_rad) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double theta = half_fov_rad * std::sqrt(u(*rng));
  const double phi = 2.0 * M_PI * u(*rng);
  const Eigen::Vector3d dir(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                            std::cos(theta));
  return (2.0 + 6.0 * u(*rng)) * dir;
}

Eigen::Vector3d Perturb(const Eigen::Vector3d& f, double sigma_rad, std::mt19937* rng) {
  if (sigma_rad <= 0.0) return f;
  std::normal_distribution<double> n(0.0, sigma_rad);
  const Eigen::Matrix<double, 3, 2> b = TangentBasis(f);
  const double y = n(*rng);  // y first, as RandomVector3 draws z first
  return (f + b * Eigen::Vector2d(n(*rng), y)).normalized();
}

struct TwoViews {
  RelativePose truth;                   // view 2 in view 1
  std::vector<Eigen::Vector3d> points;  // view 1 frame
  std::vector<Eigen::Vector3d> f1, f2;
};

TwoViews MakeTwoViews(std::mt19937* rng, int n, double half_fov_rad, double sigma_rad) {
  TwoViews v;
  v.truth.R_1_from_2 = RandomRotation(rng, 20 * kDeg);
  std::normal_distribution<double> g(0.0, 1.0);
  v.truth.C2_in_1 = RandomVector3(g, *rng).normalized() * 0.5;
  while (static_cast<int>(v.points.size()) < n) {
    const Eigen::Vector3d p1 = RandomPoint(rng, half_fov_rad);
    const Eigen::Vector3d p2 = v.truth.R_1_from_2.transpose() * (p1 - v.truth.C2_in_1);
    if (std::acos(p2.normalized().z()) > half_fov_rad) continue;
    v.points.push_back(p1);
    v.f1.push_back(Perturb(p1.normalized(), sigma_rad, rng));
    v.f2.push_back(Perturb(p2.normalized(), sigma_rad, rng));
  }
  return v;
}

TEST(FivePoint, ExactDataHasTheTrueSolution) {
  std::mt19937 rng(1);
  for (const double half_fov : {30 * kDeg, 93 * kDeg}) {
    int found = 0;
    for (int trial = 0; trial < 100; ++trial) {
      const TwoViews v = MakeTwoViews(&rng, 5, half_fov, 0.0);
      std::array<Eigen::Vector3d, 5> a, b;
      for (int i = 0; i < 5; ++i) {
        a[i] = v.f1[i];
        b[i] = v.f2[i];
      }
      const Eigen::Matrix3d truth = EssentialFromPose(v.truth).normalized();
      double best = 1e9;
      for (const Eigen::Matrix3d& E : SolveEssentialFivePoint(a, b)) {
        best = std::min({best, (E - truth).norm(), (E + truth).norm()});
        for (int i = 0; i < 5; ++i) EXPECT_LT(std::abs(a[i].dot(E * b[i])), 1e-8);
      }
      found += best < 1e-6;
    }
    EXPECT_GE(found, 98) << "half fov " << half_fov / kDeg;
  }
}

TEST(FivePoint, DecompositionRecoversPoseIncludingBearingsBehindTheImagePlane) {
  std::mt19937 rng(2);
  const TwoViews v = MakeTwoViews(&rng, 200, 93 * kDeg, 0.0);
  int behind = 0;
  for (const auto& f : v.f1) behind += f.z() <= 0.0;
  EXPECT_GT(behind, 0);  // the 186-degree field of view has bearings with z <= 0
  RelativePoseRansacOptions options;
  options.max_epipolar_angle_rad = 1e-4;
  const RelativePoseRansacResult r = EstimateRelativePose(v.f1, v.f2, options, &rng);
  ASSERT_TRUE(r.success);
  EXPECT_EQ(r.num_inliers, 200);
  EXPECT_EQ(r.num_in_front, 200);
  EXPECT_LT(RotationAngle(r.pose.R_1_from_2, v.truth.R_1_from_2), 1e-6);
  EXPECT_LT(VectorAngle(r.pose.C2_in_1, v.truth.C2_in_1), 1e-6);
}

TEST(FivePoint, RansacWithNoiseAndOutliers) {
  std::mt19937 rng(3);
  for (const double half_fov : {30 * kDeg, 93 * kDeg}) {
    const double pixel = half_fov / 376.0;  // ~ one pixel of a 752-pixel-wide image
    TwoViews v = MakeTwoViews(&rng, 300, half_fov, 0.5 * pixel);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < 60; ++i) {  // 20 % gross outliers
      v.f2[i] = (RandomVector3(u, rng) + Eigen::Vector3d(0.0, 0.0, 1.5)).normalized();
    }
    RelativePoseRansacOptions options;
    options.max_epipolar_angle_rad = 2.0 * pixel;
    const RelativePoseRansacResult r = EstimateRelativePose(v.f1, v.f2, options, &rng);
    ASSERT_TRUE(r.success);
    EXPECT_GE(r.num_inliers, 230);
    EXPECT_LT(RotationAngle(r.pose.R_1_from_2, v.truth.R_1_from_2), 0.1 * kDeg);
    EXPECT_LT(VectorAngle(r.pose.C2_in_1, v.truth.C2_in_1), 2.0 * kDeg);
  }
}

TEST(BestRotation, RecoversPureRotation) {
  std::mt19937 rng(4);
  const Eigen::Matrix3d r = RandomRotation(&rng, 40 * kDeg);
  std::vector<Eigen::Vector3d> f1, f2;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d p = RandomPoint(&rng, 80 * kDeg).normalized();
    f1.push_back(p);
    f2.push_back(r.transpose() * p);
  }
  EXPECT_LT(RotationAngle(BestRotation(f1, f2), r), 1e-9);
}

TEST(Triangulation, MidpointOfExactRaysIsThePoint) {
  const Eigen::Vector3d point(0.3, -2.0, -1.0);  // behind both image planes (z < 0)
  const Eigen::Vector3d ca(0, 0, 0), cb(1, 0.2, 0);
  const auto t = TriangulateMidpoint(ca, (point - ca).normalized(), cb, (point - cb).normalized());
  ASSERT_TRUE(t.has_value());
  EXPECT_LT((t->point - point).norm(), 1e-12);
  EXPECT_GT(t->ray_angle_rad, 0.1);
  // Rays pointing away from each other do not meet in front of both cameras.
  EXPECT_FALSE(TriangulateMidpoint(ca, -(point - ca).normalized(), cb, -(point - cb).normalized())
                   .has_value());
  // Parallel rays.
  EXPECT_FALSE(
      TriangulateMidpoint(ca, Eigen::Vector3d::UnitZ(), cb, Eigen::Vector3d::UnitZ()).has_value());
}

struct PnpData {
  CameraPoseRC truth;
  std::vector<Eigen::Vector3d> f, X;
};

PnpData MakePnp(std::mt19937* rng, int n, double half_fov_rad, double sigma_rad) {
  PnpData d;
  d.truth.R_world_from_cam = RandomRotation(rng, M_PI);
  std::normal_distribution<double> g(0.0, 1.0);
  d.truth.C = RandomVector3(g, *rng);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p_cam = RandomPoint(rng, half_fov_rad);
    d.X.push_back(d.truth.R_world_from_cam * p_cam + d.truth.C);
    d.f.push_back(Perturb(p_cam.normalized(), sigma_rad, rng));
  }
  return d;
}

TEST(P3P, ExactDataHasTheTrueSolution) {
  std::mt19937 rng(5);
  for (const double half_fov : {30 * kDeg, 93 * kDeg}) {
    int found = 0;
    for (int trial = 0; trial < 200; ++trial) {
      const PnpData d = MakePnp(&rng, 3, half_fov, 0.0);
      double best = 1e9;
      for (const CameraPoseRC& pose :
           SolveP3P({d.f[0], d.f[1], d.f[2]}, {d.X[0], d.X[1], d.X[2]})) {
        best = std::min(best, RotationAngle(pose.R_world_from_cam, d.truth.R_world_from_cam) +
                                  (pose.C - d.truth.C).norm());
      }
      found += best < 1e-6;
    }
    EXPECT_GE(found, 196) << "half fov " << half_fov / kDeg;
  }
}

TEST(Pnp, RansacAndRefinementWithNoiseAndOutliers) {
  std::mt19937 rng(6);
  for (const double half_fov : {30 * kDeg, 93 * kDeg}) {
    const double pixel = half_fov / 376.0;
    PnpData d = MakePnp(&rng, 200, half_fov, 0.5 * pixel);
    std::normal_distribution<double> g(0.0, 1.0);
    for (int i = 0; i < 50; ++i) d.X[i] += RandomVector3(g, rng);
    PnpRansacOptions options;
    options.max_angle_rad = 2.5 * pixel;
    PnpRansacResult r = EstimateAbsolutePose(d.f, d.X, options, nullptr, &rng);
    ASSERT_TRUE(r.success);
    EXPECT_GE(r.num_inliers, 140);
    ASSERT_TRUE(RefineAbsolutePose(d.f, d.X, r.inliers, 2.0 * pixel, 10, &r.pose));
    EXPECT_LT(RotationAngle(r.pose.R_world_from_cam, d.truth.R_world_from_cam), 0.05 * kDeg);
    EXPECT_LT((r.pose.C - d.truth.C).norm(), 0.02);
  }
}

TEST(Pnp, RefinementConvergesFromAPerturbedPose) {
  std::mt19937 rng(7);
  const PnpData d = MakePnp(&rng, 100, 93 * kDeg, 0.0);
  CameraPoseRC start = d.truth;
  start.R_world_from_cam = start.R_world_from_cam * ExpSO3(Eigen::Vector3d(0.05, -0.03, 0.04));
  start.C += Eigen::Vector3d(0.1, -0.05, 0.08);
  ASSERT_TRUE(RefineAbsolutePose(d.f, d.X, {}, 1.0, 20, &start));
  EXPECT_LT(RotationAngle(start.R_world_from_cam, d.truth.R_world_from_cam), 1e-7);
  EXPECT_LT((start.C - d.truth.C).norm(), 1e-7);
}

TEST(Pnp, PriorThatFitsEndsRansacEarly) {
  std::mt19937 rng(8);
  const PnpData d = MakePnp(&rng, 150, 30 * kDeg, 0.0);
  PnpRansacOptions options;
  const PnpRansacResult r = EstimateAbsolutePose(d.f, d.X, options, &d.truth, &rng);
  ASSERT_TRUE(r.success);
  EXPECT_EQ(r.num_inliers, 150);
  EXPECT_LE(r.iterations, 1);
}

}  // namespace
}  // namespace rigcal::vo
