// SPDX-License-Identifier: Apache-2.0
#pragma once
// Absolute pose (PnP) from 2D-3D matches given as unit bearing vectors in the camera frame and
// 3D points in the world frame: a P3P minimal solver on bearings (distances from the law of
// cosines, resultant quartic, absolute orientation), a RANSAC scored by angular residuals, and
// a motion-only Gauss-Newton refinement of angular residuals with a Huber weight. Bearings
// may point anywhere on the sphere (fisheye lenses wider than 180 degrees).

#include <Eigen/Core>
#include <array>
#include <random>
#include <vector>

namespace rigcal::vo {

// Camera pose: p_world = R_world_from_cam * p_cam + C.
struct CameraPoseRC {
  Eigen::Matrix3d R_world_from_cam = Eigen::Matrix3d::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
};

// Up to 4 poses that see points X[i] along bearings f[i] (unit, camera frame).
std::vector<CameraPoseRC> SolveP3P(const std::array<Eigen::Vector3d, 3>& f,
                                   const std::array<Eigen::Vector3d, 3>& X);

// Angle between the bearing f (camera frame) and the direction to X seen from `pose`, rad.
double AngularResidual(const CameraPoseRC& pose, const Eigen::Vector3d& f,
                       const Eigen::Vector3d& X);

struct PnpRansacOptions {
  double max_angle_rad = 3e-3;  // inlier threshold
  int max_iterations = 200;
  double confidence = 0.999;
  int min_inliers = 10;
};

struct PnpRansacResult {
  bool success = false;
  CameraPoseRC pose;
  std::vector<char> inliers;
  int num_inliers = 0;
  int iterations = 0;
};

// RANSAC over P3P samples. `prior` (may be null): a predicted pose scored first; when it
// already explains most matches the RANSAC ends early. `rng` must not be null.
PnpRansacResult EstimateAbsolutePose(const std::vector<Eigen::Vector3d>& f,
                                     const std::vector<Eigen::Vector3d>& X,
                                     const PnpRansacOptions& options, const CameraPoseRC* prior,
                                     std::mt19937* rng);

// Motion-only refinement: minimises sum of Huber(angular residual) over the matches with
// mask[i] != 0 (mask may be empty = all), starting from *pose. Returns false (and leaves
// *pose) when the system is degenerate. `huber_rad` is the Huber threshold.
bool RefineAbsolutePose(const std::vector<Eigen::Vector3d>& f,
                        const std::vector<Eigen::Vector3d>& X, const std::vector<char>& mask,
                        double huber_rad, int max_iterations, CameraPoseRC* pose);

// Orthonormal 3x2 basis of the plane perpendicular to the unit vector f.
Eigen::Matrix<double, 3, 2> TangentBasis(const Eigen::Vector3d& f);

// Rotation matrix of the rotation vector w (axis * angle, radians).
Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w);

}  // namespace rigcal::vo
