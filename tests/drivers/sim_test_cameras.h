#pragma once
// Small camera models for the simulated-rig tests (independent of vo/'s models, so these tests
// check the renderer against a projection they define themselves): an ideal pinhole and an
// ideal equidistant fisheye that sees beyond 180 degrees.

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <optional>
#include <string>

#include "rigcal/camera/camera_model.h"

namespace rigcal::drivers::testing {

class TestPinhole final : public camera::CameraModel {
 public:
  TestPinhole(int width, int height, double fx, double fy, double cx, double cy)
      : CameraModel(width, height), fx_(fx), fy_(fy), cx_(cx), cy_(cy) {}
  // Square pixels, principal point in the centre, horizontal field of view `hfov_deg`.
  static std::shared_ptr<TestPinhole> WithFov(int width, int height, double hfov_deg) {
    const double f = 0.5 * width / std::tan(0.5 * hfov_deg * M_PI / 180.0);
    return std::make_shared<TestPinhole>(width, height, f, f, 0.5 * (width - 1),
                                         0.5 * (height - 1));
  }
  std::string type() const override { return "pinhole"; }
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    if (p.z() <= 1e-12) return std::nullopt;
    if (jacobian) {
      *jacobian << fx_ / p.z(), 0, -fx_ * p.x() / (p.z() * p.z()), 0, fy_ / p.z(),
          -fy_ * p.y() / (p.z() * p.z());
    }
    return Eigen::Vector2d(cx_ + fx_ * p.x() / p.z(), cy_ + fy_ * p.y() / p.z());
  }
  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    if (jacobian) jacobian->setZero();
    return Eigen::Vector3d((px.x() - cx_) / fx_, (px.y() - cy_) / fy_, 1.0).normalized();
  }
  double MaxFieldAngleDeg() const override {
    const double x = std::max(cx_, width() - 1 - cx_) / fx_;
    const double y = std::max(cy_, height() - 1 - cy_) / fy_;
    return std::atan(std::hypot(x, y)) * 180.0 / M_PI;
  }
  double PixelAngle() const override { return 1.0 / fx_; }
  std::unique_ptr<CameraModel> Clone() const override {
    return std::make_unique<TestPinhole>(*this);
  }
  double fx() const { return fx_; }

 private:
  double fx_, fy_, cx_, cy_;
};

// r = f * theta; valid up to max_angle_deg from the optical axis (may exceed 90).
class TestEquidistant final : public camera::CameraModel {
 public:
  TestEquidistant(int width, int height, double f, double max_angle_deg)
      : CameraModel(width, height),
        f_(f),
        cx_(0.5 * (width - 1)),
        cy_(0.5 * (height - 1)),
        max_angle_(max_angle_deg * M_PI / 180.0) {}
  std::string type() const override { return "fisheye"; }
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    const double n = p.norm();
    if (n < 1e-12) return std::nullopt;
    const double theta = std::acos(std::clamp(p.z() / n, -1.0, 1.0));
    if (theta > max_angle_) return std::nullopt;
    const double rho = std::hypot(p.x(), p.y());
    const double r = f_ * theta;
    const Eigen::Vector2d dir =
        rho > 1e-15 ? Eigen::Vector2d(p.x() / rho, p.y() / rho) : Eigen::Vector2d(1.0, 0.0);
    if (jacobian) jacobian->setZero();
    return Eigen::Vector2d(cx_ + r * dir.x(), cy_ + r * dir.y());
  }
  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& px,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    if (jacobian) jacobian->setZero();
    const double dx = px.x() - cx_, dy = px.y() - cy_;
    const double r = std::hypot(dx, dy);
    const double theta = r / f_;
    if (theta > max_angle_) return std::nullopt;
    if (r < 1e-15) return Eigen::Vector3d(0, 0, 1);
    return Eigen::Vector3d(std::sin(theta) * dx / r, std::sin(theta) * dy / r, std::cos(theta));
  }
  double MaxFieldAngleDeg() const override { return max_angle_ * 180.0 / M_PI; }
  double PixelAngle() const override { return 1.0 / f_; }
  std::unique_ptr<CameraModel> Clone() const override {
    return std::make_unique<TestEquidistant>(*this);
  }

 private:
  double f_, cx_, cy_, max_angle_;
};

}  // namespace rigcal::drivers::testing
