// SPDX-License-Identifier: Apache-2.0
// Pinhole camera with radial-tangential distortion (OpenCV / Kalibr "radtan").
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "camera_models.h"

namespace rigcal::camera::internal {
namespace {

// Largest automatic field angle; keeps x/z finite and well away from the pole at 90 degrees.
constexpr double kPinholeMaxAutomaticFieldAngleDeg = 89.0;
// Directions sampled when scanning the distortion for a fold.
constexpr int kFoldDirections = 64;

class PinholeCamera final : public CameraModel {
 public:
  explicit PinholeCamera(const CameraSpec& spec)
      : CameraModel(spec.width, spec.height),
        fx_(spec.intrinsics[0]),
        fy_(spec.intrinsics[1]),
        cx_(spec.intrinsics[2]),
        cy_(spec.intrinsics[3]) {
    const std::vector<double>& k = spec.distortion;
    if (k.size() >= 4) {
      k1_ = k[0];
      k2_ = k[1];
      p1_ = k[2];
      p2_ = k[3];
    }
    if (k.size() >= 5) k3_ = k[4];
  }

  // Analyses the distortion and sets the domain; the first problem as "<field>: <what>".
  Status Initialise(double max_field_angle_deg);

  std::string type() const override { return "pinhole"; }

  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& point,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    if (!(point.z() > 0.0)) return std::nullopt;
    const double inv_z = 1.0 / point.z();
    const Eigen::Vector2d normalized(point.x() * inv_z, point.y() * inv_z);
    if (!(normalized.squaredNorm() <= r_max2_)) return std::nullopt;
    Eigen::Vector2d distorted;
    Eigen::Matrix2d d_distorted;
    Distort(normalized, &distorted, jacobian ? &d_distorted : nullptr);
    if (jacobian) {
      // d normalized / d point = [1/z 0 -x/z^2; 0 1/z -y/z^2].
      Eigen::Matrix<double, 2, 3> d_normalized;
      d_normalized << inv_z, 0.0, -normalized.x() * inv_z, 0.0, inv_z, -normalized.y() * inv_z;
      *jacobian = d_distorted * d_normalized;
      jacobian->row(0) *= fx_;
      jacobian->row(1) *= fy_;
    }
    return Eigen::Vector2d(fx_ * distorted.x() + cx_, fy_ * distorted.y() + cy_);
  }

  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& pixel,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    const Eigen::Vector2d distorted((pixel.x() - cx_) / fx_, (pixel.y() - cy_) / fy_);
    if (!(distorted.squaredNorm() <= distorted_bound2_)) return std::nullopt;
    Eigen::Vector2d normalized;
    Eigen::Matrix2d d_distorted;
    if (!Undistort(distorted, &normalized, &d_distorted)) return std::nullopt;
    if (!(normalized.squaredNorm() <= r_max2_ * (1.0 + 1e-12))) return std::nullopt;
    const Eigen::Vector3d ray(normalized.x(), normalized.y(), 1.0);
    const double inv_norm = 1.0 / ray.norm();
    const Eigen::Vector3d bearing = ray * inv_norm;
    if (jacobian) {
      // d bearing / d ray = (I - b b^T) / |ray|; ray depends on the first two coordinates.
      const Eigen::Matrix<double, 3, 2> d_bearing_d_normalized =
          (Eigen::Matrix3d::Identity() - bearing * bearing.transpose()).leftCols<2>() * inv_norm;
      Eigen::Matrix2d d_normalized_d_pixel = d_distorted.inverse();
      d_normalized_d_pixel.col(0) /= fx_;
      d_normalized_d_pixel.col(1) /= fy_;
      *jacobian = d_bearing_d_normalized * d_normalized_d_pixel;
    }
    return bearing;
  }

  double MaxFieldAngleDeg() const override { return max_field_angle_deg_; }
  double PixelAngle() const override { return pixel_angle_; }
  std::unique_ptr<CameraModel> Clone() const override {
    return std::make_unique<PinholeCamera>(*this);
  }

 private:
  // Distorted normalized coordinates of undistorted ones, and optionally the 2x2 Jacobian.
  void Distort(const Eigen::Vector2d& n, Eigen::Vector2d* d, Eigen::Matrix2d* jacobian) const {
    const double x = n.x();
    const double y = n.y();
    const double xx = x * x;
    const double yy = y * y;
    const double xy = x * y;
    const double r2 = xx + yy;
    const double radial = 1.0 + r2 * (k1_ + r2 * (k2_ + r2 * k3_));
    d->x() = x * radial + 2.0 * p1_ * xy + p2_ * (r2 + 2.0 * xx);
    d->y() = y * radial + p1_ * (r2 + 2.0 * yy) + 2.0 * p2_ * xy;
    if (jacobian) {
      // d radial / d r2
      const double radial_slope = k1_ + r2 * (2.0 * k2_ + 3.0 * k3_ * r2);
      (*jacobian)(0, 0) = radial + 2.0 * xx * radial_slope + 2.0 * p1_ * y + 6.0 * p2_ * x;
      (*jacobian)(0, 1) = 2.0 * xy * radial_slope + 2.0 * p1_ * x + 2.0 * p2_ * y;
      (*jacobian)(1, 0) = 2.0 * xy * radial_slope + 2.0 * p1_ * x + 2.0 * p2_ * y;
      (*jacobian)(1, 1) = radial + 2.0 * yy * radial_slope + 6.0 * p1_ * y + 2.0 * p2_ * x;
    }
  }

  // Undistorted normalized coordinates of distorted ones by Newton's method, and the distortion
  // Jacobian at the solution. Starts from target / radial(|target|) (the first step of the
  // usual fixed-point iteration); a step that does not reduce the residual is halved. Stops after
  // a full step below 1e-9 (quadratic convergence leaves an error ~1e-18). False when it does not
  // converge or reaches a fold.
  bool Undistort(const Eigen::Vector2d& target, Eigen::Vector2d* n,
                 Eigen::Matrix2d* jacobian) const {
    const double t2 = target.squaredNorm();
    const double radial = 1.0 + t2 * (k1_ + t2 * (k2_ + t2 * k3_));
    Eigen::Vector2d x = radial > 0.5 ? Eigen::Vector2d(target / radial) : target;
    Eigen::Vector2d d;
    Distort(x, &d, jacobian);
    Eigen::Vector2d residual = d - target;
    double residual2 = residual.squaredNorm();
    for (int iteration = 0; iteration < 50 && residual2 > 0.0; ++iteration) {
      if (!(jacobian->determinant() > 0.0)) return false;  // folded: outside the domain
      Eigen::Vector2d step = jacobian->inverse() * residual;
      const bool last = step.squaredNorm() <= 1e-18 * (1.0 + x.squaredNorm());
      if (last) {
        x -= step;
        Distort(x, &d, jacobian);
        residual = d - target;
        residual2 = residual.squaredNorm();
        break;
      }
      // Damping: halve the step until the residual decreases.
      bool decreased = false;
      for (int halving = 0; halving < 30 && !decreased; ++halving) {
        const Eigen::Vector2d trial = x - step;
        Eigen::Vector2d trial_d;
        Eigen::Matrix2d trial_jacobian;
        Distort(trial, &trial_d, &trial_jacobian);
        const Eigen::Vector2d trial_residual = trial_d - target;
        if (trial_residual.squaredNorm() < residual2) {
          x = trial;
          residual = trial_residual;
          residual2 = residual.squaredNorm();
          *jacobian = trial_jacobian;
          decreased = true;
        } else {
          step *= 0.5;
        }
      }
      if (!decreased) break;  // at the rounding level already
    }
    *n = x;
    return std::sqrt(residual2) <= 1e-12 * (1.0 + target.norm());
  }

  double fx_, fy_, cx_, cy_;
  double k1_ = 0.0, k2_ = 0.0, p1_ = 0.0, p2_ = 0.0, k3_ = 0.0;
  double r_max2_ = 0.0;            // squared undistorted normalized radius of the domain
  double distorted_bound2_ = 0.0;  // squared distorted radius beyond which no pixel is valid
  double max_field_angle_deg_ = 0.0;
  double pixel_angle_ = 0.0;
};

Status PinholeCamera::Initialise(double max_field_angle_deg) {
  const bool automatic = max_field_angle_deg == 0.0;
  const double r_cap =
      std::tan((automatic ? kPinholeMaxAutomaticFieldAngleDeg : max_field_angle_deg) * kDegToRad);

  // Scan outwards for the first radius where the distortion stops being one-to-one: the
  // Jacobian determinant or the radial growth of |distorted| is not positive.
  double r_fold = r_cap;
  bool folds = false;
  double r_previous = 0.0;
  for (double r = std::min(0.002, r_cap); !folds;
       r = std::min(r_cap, r < 0.2 ? r + 0.002 : r * 1.01)) {
    for (int i = 0; i < kFoldDirections; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / kFoldDirections;
      const Eigen::Vector2d direction(std::cos(angle), std::sin(angle));
      Eigen::Vector2d d;
      Eigen::Matrix2d jacobian;
      Distort(r * direction, &d, &jacobian);
      if (!(jacobian.determinant() > 0.0) || !(d.dot(jacobian * direction) > 0.0)) {
        folds = true;
        r_fold = r_previous;
        break;
      }
    }
    if (r >= r_cap) break;
    r_previous = r;
  }
  if (folds && !automatic) {
    std::ostringstream what;
    what << "the radial-tangential distortion folds back at a field angle of "
         << std::atan(r_fold) * kRadToDeg << " deg; max_field_angle_deg must not exceed that";
    return Issue("max_field_angle_deg", what.str());
  }
  if (!(r_fold > 0.0)) {
    return Issue("distortion", "the distortion folds back at the principal point");
  }
  r_max2_ = r_fold * r_fold;
  const auto update_bound = [this]() {
    const double r_max = std::sqrt(r_max2_);
    double bound = 0.0;
    for (int i = 0; i < 720; ++i) {
      const double angle = 2.0 * std::numbers::pi * i / 720;
      Eigen::Vector2d d;
      Distort(r_max * Eigen::Vector2d(std::cos(angle), std::sin(angle)), &d, nullptr);
      bound = std::max(bound, d.norm());
    }
    bound *= 1.001;  // between the sampled directions
    distorted_bound2_ = bound * bound;
  };
  update_bound();

  if (automatic) {
    // The farthest undistorted radius of the image border (|undistorted| has no interior
    // maximum: the map is a diffeomorphism whose only critical point of |n|^2 is n = 0).
    double r_border = 0.0;
    bool inside = true;
    const auto visit = [&](double u, double v) {
      const Eigen::Vector2d distorted((u - cx_) / fx_, (v - cy_) / fy_);
      Eigen::Vector2d n;
      Eigen::Matrix2d jacobian;
      if (distorted.squaredNorm() > distorted_bound2_ || !Undistort(distorted, &n, &jacobian) ||
          n.squaredNorm() > r_max2_) {
        inside = false;
      } else {
        r_border = std::max(r_border, n.norm());
      }
    };
    const double u_max = width() - 0.5;
    const double v_max = height() - 0.5;
    for (double u = -0.5; u <= u_max; u += 0.5) {
      visit(u, -0.5);
      visit(u, v_max);
    }
    for (double v = -0.5; v <= v_max; v += 0.5) {
      visit(-0.5, v);
      visit(u_max, v);
    }
    if (inside) {
      r_max2_ = std::min(r_max2_, std::pow(r_border * (1.0 + 1e-6), 2));
      update_bound();
    }
  }
  max_field_angle_deg_ = std::atan(std::sqrt(r_max2_)) * kRadToDeg;

  if (!PixelAngleAt(*this, Eigen::Vector2d(cx_, cy_), &pixel_angle_)) {
    return Issue("distortion", "cannot unproject the principal point");
  }
  return Status::Ok();
}

}  // namespace

Expected<std::unique_ptr<CameraModel>> BuildPinholeCamera(const CameraSpec& spec) {
  auto camera = std::make_unique<PinholeCamera>(spec);
  if (Status status = camera->Initialise(spec.max_field_angle_deg); !status.ok()) return status;
  return std::unique_ptr<CameraModel>(std::move(camera));
}

}  // namespace rigcal::camera::internal
