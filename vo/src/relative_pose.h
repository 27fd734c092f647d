// SPDX-License-Identifier: Apache-2.0
#pragma once
// Relative pose of two views from bearing-vector correspondences: the minimal 5-point
// essential-matrix solver (Stewenius/Nister, Groebner basis with an action matrix), its
// decomposition and a RANSAC around it. Everything works on unit bearing vectors, never on
// normalised image coordinates, so bearings with z <= 0 (lenses wider than 180 degrees) are
// fine.
//
// Convention: view 2's pose in view 1's frame, p_in_1 = R_1_from_2 * p_in_2 + C2_in_1. With
// bearings f1 ~ p_in_1 and f2 ~ p_in_2 the epipolar constraint is f1^T E f2 = 0 with
// E = [C2_in_1]x R_1_from_2 (thesis eq. 3.22).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <random>
#include <vector>

namespace rigcal::vo {

struct RelativePose {
  Eigen::Matrix3d R_1_from_2 = Eigen::Matrix3d::Identity();
  Eigen::Vector3d C2_in_1 = Eigen::Vector3d::Zero();
};

// Essential matrix E = [C]x R of a relative pose.
Eigen::Matrix3d EssentialFromPose(const RelativePose& pose);

// Up to 10 essential matrices (unit Frobenius norm) consistent with 5 correspondences
// f1[i] <-> f2[i] (unit or any-length bearings). Empty for degenerate samples.
std::vector<Eigen::Matrix3d> SolveEssentialFivePoint(const std::array<Eigen::Vector3d, 5>& f1,
                                                     const std::array<Eigen::Vector3d, 5>& f2);

// Epipolar error of a correspondence in radians: the larger of the angles between f1 and the
// epipolar plane of f2, and between f2 and the epipolar plane of f1. Unit bearings.
double EpipolarAngle(const Eigen::Matrix3d& E, const Eigen::Vector3d& f1,
                     const Eigen::Vector3d& f2);

// The four (R, C) with ||C|| = 1 that an essential matrix factors into.
std::array<RelativePose, 4> DecomposeEssential(const Eigen::Matrix3d& E);

// Depths d1, d2 along the two rays with d1 f1 ~= d2 R f2 + C (closest points of the rays).
// Returns false when the rays are parallel.
bool RayDepths(const RelativePose& pose, const Eigen::Vector3d& f1, const Eigen::Vector3d& f2,
               double* d1, double* d2);

// How many of the correspondences marked in `inliers` triangulate in front of both views with
// `pose` (RayDepths positive).
int InliersInFront(const RelativePose& pose, const std::vector<Eigen::Vector3d>& f1,
                   const std::vector<Eigen::Vector3d>& f2, const std::vector<char>& inliers);

// The rotation R (1_from_2) minimising sum ||f1 - R f2||^2 over the given pairs (Kabsch).
Eigen::Matrix3d BestRotation(const std::vector<Eigen::Vector3d>& f1,
                             const std::vector<Eigen::Vector3d>& f2);

struct RelativePoseRansacOptions {
  double max_epipolar_angle_rad = 2e-3;  // inlier threshold (EpipolarAngle)
  int max_iterations = 200;
  double confidence = 0.999;
  int min_inliers = 15;
};

struct RelativePoseRansacResult {
  bool success = false;
  RelativePose pose;  // the decomposition with most points in front of both views
  // The best model found (also when too few inliers support it: its epipolar distances still
  // measure the noise; zero when no sample gave a model).
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  std::vector<char> inliers;  // epipolar inliers of E
  int num_inliers = 0;
  int num_in_front = 0;  // inliers that triangulate in front of both views with `pose`
  int iterations = 0;
};

// RANSAC of the 5-point solver over unit-bearing correspondences f1[i] <-> f2[i]. `rng` must
// not be null. Deterministic for a given rng state.
RelativePoseRansacResult EstimateRelativePose(const std::vector<Eigen::Vector3d>& f1,
                                              const std::vector<Eigen::Vector3d>& f2,
                                              const RelativePoseRansacOptions& options,
                                              std::mt19937* rng);

}  // namespace rigcal::vo
