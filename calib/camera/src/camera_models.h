// SPDX-License-Identifier: Apache-2.0
#pragma once
// Private to rigcal_camera: the builders of the three camera models and the numeric helpers they
// share.

#include <cmath>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_model.h"
#include "rigcal/camera/camera_spec.h"

namespace rigcal::camera::internal {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// A problem of a CameraSpec: "<field>: <what>", `field` being the config key at fault
// (`intrinsics`, `distortion`, `poly`, ...).
inline Status Issue(std::string_view field, const std::string& what) {
  return Error{std::string(field) + ": " + what};
}

// Builders. `spec` has passed the structural checks of CameraSpec::Check (sizes, ranges,
// finite values). On a lens-model problem they return the Issue.
Expected<std::unique_ptr<CameraModel>> BuildPinholeCamera(const CameraSpec& spec);
Expected<std::unique_ptr<CameraModel>> BuildFisheyeCamera(const CameraSpec& spec);
Expected<std::unique_ptr<CameraModel>> BuildScaramuzzaCamera(const CameraSpec& spec);

// The angle one pixel subtends at `pixel` (radians): the square root of the area the
// unprojection Jacobian maps a pixel to on the unit sphere. False when `pixel` does not
// unproject.
inline bool PixelAngleAt(const CameraModel& camera, const Eigen::Vector2d& pixel, double* angle) {
  Eigen::Matrix<double, 3, 2> jacobian;
  if (!camera.Unproject(pixel, &jacobian)) return false;
  *angle = std::sqrt(std::sqrt((jacobian.transpose() * jacobian).determinant()));
  return true;
}

// sum_i c[i] x^i (Horner). Empty c: 0.
inline double Polynomial(const std::vector<double>& c, double x) {
  double value = 0.0;
  for (auto it = c.rbegin(); it != c.rend(); ++it) value = value * x + *it;
  return value;
}

// sum_i c[i] x^i and its derivative.
inline double Polynomial(const std::vector<double>& c, double x, double* derivative) {
  double value = 0.0;
  double slope = 0.0;
  for (auto it = c.rbegin(); it != c.rend(); ++it) {
    slope = slope * x + value;
    value = value * x + *it;
  }
  *derivative = slope;
  return value;
}

// Root of a function that is increasing on [lo, hi] with f(lo) <= 0 <= f(hi), by Newton's
// method from `x` safeguarded with bisection (a step leaving the bracket bisects instead).
// `f(x, &slope)` returns the value and sets the derivative. Returns after a Newton step of at
// most newton_tol (Newton converges quadratically: the error left is ~newton_tol^2 times the
// curvature ratio f'' / 2f'), or when the bracket has shrunk to bracket_tol. Allocation-free; at
// most 200 evaluations.
template <typename Function>
double SolveIncreasing(const Function& f, double x, double lo, double hi, double newton_tol,
                       double bracket_tol) {
  if (!(x > lo && x < hi)) x = 0.5 * (lo + hi);
  for (int iteration = 0; iteration < 200; ++iteration) {
    double slope = 0.0;
    const double value = f(x, &slope);
    if (value == 0.0) return x;
    if (value < 0.0) {
      lo = x;
    } else {
      hi = x;
    }
    const double newton = x - value / slope;
    if (slope > 0.0 && newton > lo && newton < hi) {
      const bool converged = std::abs(newton - x) <= newton_tol;
      x = newton;
      if (converged) break;
    } else {
      x = 0.5 * (lo + hi);
    }
    if (hi - lo <= bracket_tol) break;
  }
  return x;
}

}  // namespace rigcal::camera::internal
