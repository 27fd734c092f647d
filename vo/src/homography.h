// SPDX-License-Identifier: Apache-2.0
#pragma once
// The homography of two views of a plane (or of two views without translation) from
// bearing-vector correspondences: a RANSAC (OpenCV's findHomography on the bearings'
// normalised coordinates) judged by angular transfer errors, and its decomposition into the
// relative poses it admits (OpenCV's decomposeHomographyMat, Malis & Vargas).
//
// Convention as in relative_pose.h: p_in_1 = R_1_from_2 * p_in_2 + C2_in_1. For points on the
// plane n_in_2 . p_in_2 = d (d > 0: the distance of view 2 from the plane),
// p_in_1 = (R_1_from_2 + C2_in_1 n_in_2^T / d) p_in_2, so f1 ~ H_1_from_2 f2 with
// H_1_from_2 = R_1_from_2 + C2_in_1 n_in_2^T / d.

#include <Eigen/Core>
#include <vector>

#include "relative_pose.h"

namespace rigcal::vo {

// Transfer error of a correspondence under H (f1 ~ H f2), radians: the larger of the angles
// between f1 and H f2 and between f2 and H^-1 f1. `h_inverse` is H^-1. Unit bearings.
double HomographyTransferAngle(const Eigen::Matrix3d& h, const Eigen::Matrix3d& h_inverse,
                               const Eigen::Vector3d& f1, const Eigen::Vector3d& f2);

struct HomographyRansacOptions {
  double max_transfer_angle_rad = 2e-3;  // inlier threshold (HomographyTransferAngle)
  int max_iterations = 200;
  double confidence = 0.999;
};

struct HomographyRansacResult {
  bool success = false;  // a homography was found (whatever its support)
  Eigen::Matrix3d H_1_from_2 = Eigen::Matrix3d::Identity();
  std::vector<char> inliers;  // transfer error within the threshold
  int num_inliers = 0;
};

// RANSAC of a homography over unit-bearing correspondences f1[i] <-> f2[i]; bearings more than
// 80 degrees off the optical axis (not representable on the image plane with a useful
// conditioning) take no part and are never inliers. Deterministic (OpenCV seeds its RANSAC).
HomographyRansacResult EstimateHomography(const std::vector<Eigen::Vector3d>& f1,
                                          const std::vector<Eigen::Vector3d>& f2,
                                          const HomographyRansacOptions& options);

// One relative pose a homography admits: R_1_from_2, the direction of C2_in_1 (unit, or zero
// when the homography is a pure rotation), the plane's unit normal in view 2, and the
// translation's length over the plane's distance (|C2_in_1| / d).
struct PlanarMotion {
  RelativePose pose;
  Eigen::Vector3d normal_in_2 = Eigen::Vector3d::UnitZ();
  double baseline_over_distance = 0.0;
};

// Every decomposition of H_1_from_2 (up to four; two of them put the plane behind the views).
std::vector<PlanarMotion> DecomposeHomography(const Eigen::Matrix3d& H_1_from_2);

}  // namespace rigcal::vo
