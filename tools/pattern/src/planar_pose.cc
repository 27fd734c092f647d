// SPDX-License-Identifier: Apache-2.0
// Pose of a planar target from bearings (DLT) refined on the reprojection error.
#include "planar_pose.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace rigcal::pattern::internal {
namespace {

// Residuals (2 per corner) and, when `jacobian` is given, their derivatives with respect to a
// left rotation increment and the translation (R <- Exp(w) R, t <- t + dt). False when a
// corner does not project.
bool Residuals(const camera::CameraModel& model, const TargetView& view, const Eigen::Matrix3d& R,
               const Eigen::Vector3d& t, Eigen::VectorXd* residuals, Eigen::MatrixXd* jacobian) {
  const size_t n = view.pixels.size();
  residuals->resize(static_cast<Eigen::Index>(2 * n));
  if (jacobian != nullptr) jacobian->resize(static_cast<Eigen::Index>(2 * n), 6);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d rotated = R * view.target_points[i];
    Eigen::Matrix<double, 2, 3> d_pixel;
    const std::optional<Eigen::Vector2d> pixel =
        model.Project(rotated + t, jacobian != nullptr ? &d_pixel : nullptr);
    if (!pixel) return false;
    const auto row = static_cast<Eigen::Index>(2 * i);
    residuals->segment<2>(row) = *pixel - view.pixels[i];
    if (jacobian != nullptr) {
      Eigen::Matrix3d skew;
      skew << 0.0, -rotated.z(), rotated.y(), rotated.z(), 0.0, -rotated.x(), -rotated.y(),
          rotated.x(), 0.0;
      jacobian->block<2, 3>(row, 0) = -d_pixel * skew;
      jacobian->block<2, 3>(row, 3) = d_pixel;
    }
  }
  return true;
}

// Hartley normalisation of the target's (planar) corners: centroid at 0, mean distance sqrt(2).
Expected<Eigen::Matrix3d> NormalisingTransform(const TargetView& view) {
  const size_t n = view.target_points.size();
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  for (const Eigen::Vector3d& p : view.target_points) centroid += p.head<2>();
  centroid /= static_cast<double>(n);
  double spread = 0.0;
  for (const Eigen::Vector3d& p : view.target_points) spread += (p.head<2>() - centroid).norm();
  if (!(spread > 0.0)) return Error{view.file + ": the target's corners coincide"};
  const double k = std::sqrt(2.0) * static_cast<double>(n) / spread;
  Eigen::Matrix3d normalise;
  normalise << k, 0.0, -k * centroid.x(), 0.0, k, -k * centroid.y(), 0.0, 0.0, 1.0;
  return normalise;
}

// The homography H (target plane -> bearings) from b x (H p) = 0 for every corner (three rows of
// which two are independent), in unnormalised target coordinates; the corners' bearings too.
Expected<Eigen::Matrix3d> PlaneHomography(const camera::CameraModel& model, const TargetView& view,
                                          const Eigen::Matrix3d& normalise,
                                          std::vector<Eigen::Vector3d>* bearings) {
  const size_t n = view.pixels.size();
  Eigen::MatrixXd A(static_cast<Eigen::Index>(3 * n), 9);
  A.setZero();
  bearings->resize(n);
  for (size_t i = 0; i < n; ++i) {
    const std::optional<Eigen::Vector3d> b = model.Unproject(view.pixels[i]);
    if (!b) {
      return Error{view.file + ": corner " + std::to_string(i) +
                   " is outside the camera model's field of view"};
    }
    (*bearings)[i] = *b;
    const Eigen::Vector3d p =
        normalise * Eigen::Vector3d(view.target_points[i].x(), view.target_points[i].y(), 1.0);
    const auto r = static_cast<Eigen::Index>(3 * i);
    A.block<1, 3>(r, 3) = -b->z() * p.transpose();
    A.block<1, 3>(r, 6) = b->y() * p.transpose();
    A.block<1, 3>(r + 1, 0) = b->z() * p.transpose();
    A.block<1, 3>(r + 1, 6) = -b->x() * p.transpose();
    A.block<1, 3>(r + 2, 0) = -b->y() * p.transpose();
    A.block<1, 3>(r + 2, 3) = b->x() * p.transpose();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::VectorXd h = svd.matrixV().col(8);
  Eigen::Matrix3d H;
  H << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return Eigen::Matrix3d(H * normalise);
}

// The pose [R | t] from the homography: its first two columns scaled to unit length, the sign
// that puts the target in front of the camera, R made a rotation (polar decomposition).
Status PoseFromHomography(const Eigen::Matrix3d& H, const TargetView& view,
                          const std::vector<Eigen::Vector3d>& bearings, Eigen::Matrix3d* R,
                          Eigen::Vector3d* t) {
  double lambda = 2.0 / (H.col(0).norm() + H.col(1).norm());
  if (!std::isfinite(lambda)) return Error{view.file + ": degenerate target view"};
  double facing = 0.0;
  for (size_t i = 0; i < bearings.size(); ++i) {
    facing += bearings[i].dot(
        H * Eigen::Vector3d(view.target_points[i].x(), view.target_points[i].y(), 1.0));
  }
  if (facing < 0.0) lambda = -lambda;
  Eigen::Matrix3d R0;
  R0.col(0) = lambda * H.col(0);
  R0.col(1) = lambda * H.col(1);
  R0.col(2) = R0.col(0).cross(R0.col(1));
  const Eigen::JacobiSVD<Eigen::Matrix3d> polar(R0, Eigen::ComputeFullU | Eigen::ComputeFullV);
  *R = polar.matrixU() * polar.matrixV().transpose();
  if (R->determinant() < 0.0) {
    Eigen::Matrix3d flip = Eigen::Matrix3d::Identity();
    flip(2, 2) = -1.0;
    *R = polar.matrixU() * flip * polar.matrixV().transpose();
  }
  *t = lambda * H.col(2);
  return Status::Ok();
}

// Levenberg-Marquardt on the reprojection error from [R | t]; returns the final cost and
// residuals. Errors when a corner does not project under the initial pose.
Status RefineReprojection(const camera::CameraModel& model, const TargetView& view,
                          Eigen::Matrix3d* R, Eigen::Vector3d* t, Eigen::VectorXd* residuals,
                          double* cost_out) {
  Eigen::MatrixXd jacobian;
  if (!Residuals(model, view, *R, *t, residuals, &jacobian)) {
    return Error{view.file + ": a corner does not project under the initial target pose"};
  }
  double cost = residuals->squaredNorm();
  double damping = 1e-3;
  for (int iteration = 0; iteration < 100; ++iteration) {
    const Eigen::Matrix<double, 6, 6> JtJ = jacobian.transpose() * jacobian;
    const Eigen::Matrix<double, 6, 1> Jtr = jacobian.transpose() * *residuals;
    Eigen::Matrix<double, 6, 6> damped = JtJ;
    damped.diagonal() += damping * JtJ.diagonal().cwiseMax(1e-12);
    const Eigen::Matrix<double, 6, 1> step = damped.ldlt().solve(-Jtr);
    const Eigen::Vector3d w = step.head<3>();
    const Eigen::Matrix3d R_new =
        (w.norm() > 0.0 ? Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix()
                        : Eigen::Matrix3d::Identity()) *
        *R;
    const Eigen::Vector3d t_new = *t + step.tail<3>();
    Eigen::VectorXd new_residuals;
    Eigen::MatrixXd new_jacobian;
    if (Residuals(model, view, R_new, t_new, &new_residuals, &new_jacobian) &&
        new_residuals.squaredNorm() <= cost) {
      const double decrease = cost - new_residuals.squaredNorm();
      *R = R_new;
      *t = t_new;
      *residuals = std::move(new_residuals);
      jacobian = std::move(new_jacobian);
      cost = residuals->squaredNorm();
      damping = std::max(damping / 10.0, 1e-9);
      if (decrease <= 1e-14 * (1.0 + cost) || step.norm() < 1e-14) break;
    } else {
      damping *= 10.0;
      if (damping > 1e8) break;
    }
  }
  *cost_out = cost;
  return Status::Ok();
}

}  // namespace

bool OnTargetPlane(const TargetView& view) {
  return std::all_of(view.target_points.begin(), view.target_points.end(),
                     [](const Eigen::Vector3d& p) {
                       return std::abs(p.z()) <= 1e-9 * (1.0 + p.head<2>().norm());
                     });
}

Expected<PlanarPose> EstimatePlanarPose(const camera::CameraModel& model, const TargetView& view) {
  const size_t n = view.pixels.size();
  if (n < 4 || view.target_points.size() != n) {
    return Error{view.file + ": a target pose needs at least 4 corners"};
  }
  if (!OnTargetPlane(view)) {
    return Error{view.file + ": the target's corners are not on its z = 0 plane"};
  }
  auto normalise = NormalisingTransform(view);
  if (!normalise) return Error{normalise.error()};
  std::vector<Eigen::Vector3d> bearings;
  auto H = PlaneHomography(model, view, *normalise, &bearings);
  if (!H) return Error{H.error()};
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  if (Status s = PoseFromHomography(*H, view, bearings, &R, &t); !s.ok()) return Error{s.message()};
  Eigen::VectorXd residuals;
  double cost = 0.0;
  if (Status s = RefineReprojection(model, view, &R, &t, &residuals, &cost); !s.ok()) {
    return Error{s.message()};
  }
  PlanarPose pose;
  pose.cam_from_target_rotation = R;
  pose.cam_from_target_translation = t;
  pose.rms_px = std::sqrt(cost / static_cast<double>(n));
  for (size_t i = 0; i < n; ++i) {
    pose.max_px =
        std::max(pose.max_px, residuals.segment<2>(static_cast<Eigen::Index>(2 * i)).norm());
  }
  return pose;
}

}  // namespace rigcal::pattern::internal
