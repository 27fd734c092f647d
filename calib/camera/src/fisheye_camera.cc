// SPDX-License-Identifier: Apache-2.0
// Equidistant fisheye, Kannala-Brandt distortion (OpenCV fisheye / Kalibr "equidistant").
// Field angles beyond 90 degrees (points with z < 0) are valid up to the max field angle.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "camera_models.h"

namespace rigcal::camera::internal {
namespace {

constexpr double kFisheyeMaxAutomaticFieldAngleDeg = 179.0;
// Below this field angle (radians) the projection uses its first-order limit (error ~1e-20).
constexpr double kSmallAngle = 1e-10;
// Newton on theta (radians) stops after a step below this: the error left is ~1e-18 rad.
constexpr double kNewtonTolerance = 1e-9;
constexpr double kBracketTolerance = 1e-15;

class FisheyeCamera final : public CameraModel {
 public:
  explicit FisheyeCamera(const CameraSpec& spec)
      : CameraModel(spec.width, spec.height),
        fx_(spec.intrinsics[0]),
        fy_(spec.intrinsics[1]),
        cx_(spec.intrinsics[2]),
        cy_(spec.intrinsics[3]) {
    if (spec.distortion.size() == 4) {
      k1_ = spec.distortion[0];
      k2_ = spec.distortion[1];
      k3_ = spec.distortion[2];
      k4_ = spec.distortion[3];
    }
  }

  Status Initialise(double max_field_angle_deg);

  std::string type() const override { return "fisheye"; }

  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& point,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    const double x = point.x();
    const double y = point.y();
    const double z = point.z();
    const double r2 = x * x + y * y;
    const double r = std::sqrt(r2);
    const double theta = std::atan2(r, z);
    if (!(theta <= theta_max_)) return std::nullopt;
    Eigen::Vector2d m;
    if (theta < kSmallAngle) {
      if (!(z > 0.0)) return std::nullopt;  // the origin
      // theta_d / r -> 1 / z: the pinhole limit.
      const double inv_z = 1.0 / z;
      m = Eigen::Vector2d(x * inv_z, y * inv_z);
      if (jacobian) {
        *jacobian << fx_ * inv_z, 0.0, -fx_ * x * inv_z * inv_z, 0.0, fy_ * inv_z,
            -fy_ * y * inv_z * inv_z;
      }
    } else {
      double theta_d_slope = 0.0;
      const double theta_d = ThetaD(theta, &theta_d_slope);
      const double s = theta_d / r;  // m = s (x, y)
      m = Eigen::Vector2d(s * x, s * y);
      if (jacobian) {
        // theta = atan2(r, z): d theta / d(x, y, z) = (z x / r, z y / r, -r) / rho^2 with
        // rho^2 = r^2 + z^2. s = theta_d / r: d s / d(x, y) = a (x, y) with
        // a = (theta_d' z / rho^2 - s) / r^2, and d s / d z = b = -theta_d' / rho^2.
        // The cancellation in a costs at most eps in a x^2 since x^2 <= r^2.
        const double rho2 = r2 + z * z;
        const double a = (theta_d_slope * z / rho2 - s) / r2;
        const double b = -theta_d_slope / rho2;
        *jacobian << fx_ * (s + x * x * a), fx_ * x * y * a, fx_ * x * b, fy_ * x * y * a,
            fy_ * (s + y * y * a), fy_ * y * b;
      }
    }
    return Eigen::Vector2d(fx_ * m.x() + cx_, fy_ * m.y() + cy_);
  }

  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& pixel,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    const Eigen::Vector2d m((pixel.x() - cx_) / fx_, (pixel.y() - cy_) / fy_);
    const double theta_d = m.norm();
    if (!(theta_d <= theta_d_max_)) return std::nullopt;
    Eigen::Vector3d bearing;
    Eigen::Matrix<double, 3, 2> d_bearing_d_m;
    if (theta_d < kSmallAngle) {
      // theta = theta_d to first order: bearing ~ (m, 1), d bearing / d m ~ [I; -m^T].
      bearing = Eigen::Vector3d(m.x(), m.y(), 1.0).normalized();
      d_bearing_d_m << 1.0, 0.0, 0.0, 1.0, -m.x(), -m.y();
    } else {
      const double theta = SolveIncreasing(
          [this, theta_d](double t, double* slope) { return ThetaD(t, slope) - theta_d; }, theta_d,
          0.0, theta_max_, kNewtonTolerance, kBracketTolerance);
      double theta_d_slope = 0.0;
      ThetaD(theta, &theta_d_slope);
      const double sin_theta = std::sin(theta);
      const double cos_theta = std::cos(theta);
      const double q = sin_theta / theta_d;  // bearing_xy = q m
      bearing = Eigen::Vector3d(q * m.x(), q * m.y(), cos_theta);
      if (jacobian) {
        // d theta / d theta_d = 1 / theta_d', d theta_d / d m = m^T / theta_d.
        const double dq = (cos_theta / theta_d_slope * theta_d - sin_theta) /
                          (theta_d * theta_d * theta_d);  // (d q / d theta_d) / theta_d
        const double dz = -sin_theta / theta_d_slope / theta_d;
        d_bearing_d_m << q + m.x() * m.x() * dq, m.x() * m.y() * dq, m.x() * m.y() * dq,
            q + m.y() * m.y() * dq, dz * m.x(), dz * m.y();
      }
    }
    if (jacobian) {
      jacobian->col(0) = d_bearing_d_m.col(0) / fx_;
      jacobian->col(1) = d_bearing_d_m.col(1) / fy_;
    }
    return bearing;
  }

  double MaxFieldAngleDeg() const override { return theta_max_ * kRadToDeg; }
  double PixelAngle() const override { return pixel_angle_; }
  std::unique_ptr<CameraModel> Clone() const override {
    return std::make_unique<FisheyeCamera>(*this);
  }

 private:
  // theta_d(theta) = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8) and its
  // derivative.
  double ThetaD(double theta, double* slope) const {
    const double t2 = theta * theta;
    const double poly = 1.0 + t2 * (k1_ + t2 * (k2_ + t2 * (k3_ + t2 * k4_)));
    *slope = 1.0 + t2 * (3.0 * k1_ + t2 * (5.0 * k2_ + t2 * (7.0 * k3_ + t2 * 9.0 * k4_)));
    return theta * poly;
  }

  double fx_, fy_, cx_, cy_;
  double k1_ = 0.0, k2_ = 0.0, k3_ = 0.0, k4_ = 0.0;
  double theta_max_ = 0.0;    // radians
  double theta_d_max_ = 0.0;  // theta_d(theta_max_)
  double pixel_angle_ = 0.0;
};

Status FisheyeCamera::Initialise(double max_field_angle_deg) {
  const bool automatic = max_field_angle_deg == 0.0;
  const double theta_cap =
      (automatic ? kFisheyeMaxAutomaticFieldAngleDeg : max_field_angle_deg) * kDegToRad;
  // First angle where theta_d stops increasing.
  double theta_fold = theta_cap;
  bool folds = false;
  double previous_theta = 0.0;
  double previous_theta_d = 0.0;
  for (double theta = std::min(1e-3, theta_cap);; theta = std::min(theta_cap, theta + 1e-3)) {
    double slope = 0.0;
    const double theta_d = ThetaD(theta, &slope);
    if (!(slope > 0.0) || !(theta_d > previous_theta_d)) {
      folds = true;
      theta_fold = previous_theta;
      break;
    }
    previous_theta = theta;
    previous_theta_d = theta_d;
    if (theta >= theta_cap) break;
  }
  if (folds && !automatic) {
    std::ostringstream what;
    what << "the Kannala-Brandt distortion folds back at a field angle of "
         << theta_fold * kRadToDeg << " deg; max_field_angle_deg must not exceed that";
    return Issue("max_field_angle_deg", what.str());
  }
  if (!(theta_fold > 0.0)) {
    return Issue("distortion", "the distortion folds back at the principal point");
  }
  double slope = 0.0;
  theta_max_ = theta_fold;
  theta_d_max_ = ThetaD(theta_max_, &slope);
  if (automatic) {
    // The farthest image corner (|m| is convex in the pixel, so its maximum is at a corner).
    double corner = 0.0;
    for (const double u : {-0.5, width() - 0.5}) {
      for (const double v : {-0.5, height() - 0.5}) {
        corner = std::max(corner, std::hypot((u - cx_) / fx_, (v - cy_) / fy_));
      }
    }
    if (corner < theta_d_max_) {
      theta_max_ =
          SolveIncreasing([this, corner](double t, double* s) { return ThetaD(t, s) - corner; },
                          corner, 0.0, theta_max_, kNewtonTolerance, kBracketTolerance);
      theta_d_max_ = corner;
    }
  }
  if (!PixelAngleAt(*this, Eigen::Vector2d(cx_, cy_), &pixel_angle_)) {
    return Issue("intrinsics", "cannot unproject the principal point");
  }
  return Status::Ok();
}

}  // namespace

Expected<std::unique_ptr<CameraModel>> BuildFisheyeCamera(const CameraSpec& spec) {
  auto camera = std::make_unique<FisheyeCamera>(spec);
  if (Status status = camera->Initialise(spec.max_field_angle_deg); !status.ok()) return status;
  return std::unique_ptr<CameraModel>(std::move(camera));
}

}  // namespace rigcal::camera::internal
