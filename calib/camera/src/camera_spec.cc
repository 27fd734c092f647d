// SPDX-License-Identifier: Apache-2.0
#include "rigcal/camera/camera_spec.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>

#include "camera_models.h"
#include "rigcal/base/format.h"
#include "rigcal/base/logging.h"

namespace rigcal::camera {
namespace {

using internal::Issue;

constexpr int kMaxImageSide = 100000;
constexpr size_t kMaxPolySize = 21;         // a0..a20
constexpr size_t kMaxInversePolySize = 31;  // b0..b30

// Numbers in messages: 10 significant digits.
std::string Str(double value) { return SignificantText(value, 10); }

bool AllFinite(const std::vector<double>& values) {
  for (const double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

bool InsideImage(double u, double v, int width, int height) {
  return u >= -0.5 && u <= width - 0.5 && v >= -0.5 && v <= height - 0.5;
}

// The image's size, the field angle and the rolling shutter's readout.
Status CheckImage(const CameraSpec& spec) {
  using Model = CameraSpec::Model;
  if (!(spec.width > 0 && spec.width <= kMaxImageSide && spec.height > 0 &&
        spec.height <= kMaxImageSide)) {
    return Issue("resolution", "width and height must be in [1, " + std::to_string(kMaxImageSide) +
                                   "] (got " + std::to_string(spec.width) + " x " +
                                   std::to_string(spec.height) + ")");
  }
  const double max_angle = spec.max_field_angle_deg;
  const double angle_limit = spec.model == Model::kPinhole ? 90.0 : 180.0;
  if (!(max_angle == 0.0 || (max_angle > 0.0 && max_angle < angle_limit))) {
    return Issue("max_field_angle_deg", "must be 0 (automatic) or in (0, " + Str(angle_limit) +
                                            ") for " + std::string(ModelName(spec.model)) +
                                            " (got " + Str(max_angle) + ")");
  }
  if (!(spec.rolling_shutter_s >= 0.0 && spec.rolling_shutter_s < 1.0)) {
    return Issue("rolling_shutter_ms",
                 "must be in [0, 1000) ms (got " + Str(spec.rolling_shutter_s * 1e3) + ")");
  }
  return Status::Ok();
}

// Ranges, sizes and finiteness; the lens analysis is done by the builders.
Status CheckStructure(const CameraSpec& spec) {
  using Model = CameraSpec::Model;
  if (Status status = CheckImage(spec); !status.ok()) return status;
  const std::string model_name(ModelName(spec.model));
  if (spec.model == Model::kPinhole || spec.model == Model::kFisheye) {
    const auto& k = spec.intrinsics;
    for (const double v : k) {
      if (!std::isfinite(v)) return Issue("intrinsics", "values must be finite");
    }
    if (!(k[0] > 0.0 && k[1] > 0.0)) {
      return Issue("intrinsics",
                   "fx and fy must be > 0 (got fx " + Str(k[0]) + ", fy " + Str(k[1]) + ")");
    }
    if (!InsideImage(k[2], k[3], spec.width, spec.height)) {
      return Issue("intrinsics", "principal point (" + Str(k[2]) + ", " + Str(k[3]) +
                                     ") is outside the " + std::to_string(spec.width) + " x " +
                                     std::to_string(spec.height) + " image");
    }
    const size_t n = spec.distortion.size();
    if (spec.model == Model::kPinhole && !(n == 0 || n == 4 || n == 5)) {
      return Issue("distortion",
                   "pinhole expects [k1, k2, p1, p2] or [k1, k2, p1, p2, "
                   "k3] (got " +
                       std::to_string(n) + " values)");
    }
    if (spec.model == Model::kFisheye && !(n == 0 || n == 4)) {
      return Issue("distortion",
                   "fisheye expects [k1, k2, k3, k4] (got " + std::to_string(n) + " values)");
    }
    if (!AllFinite(spec.distortion)) {
      return Issue("distortion", "values must be finite");
    }
    if (!spec.poly.empty()) return Issue("poly", "not used by model " + model_name);
    if (!spec.inverse_poly.empty()) {
      return Issue("inverse_poly", "not used by model " + model_name);
    }
    if (spec.center != std::array<double, 2>{0.0, 0.0}) {
      return Issue("center", "not used by model " + model_name);
    }
    if (spec.affine != std::array<double, 3>{1.0, 0.0, 0.0}) {
      return Issue("affine", "not used by model " + model_name);
    }
    return Status::Ok();
  }

  // scaramuzza
  if (spec.intrinsics != std::array<double, 4>{0.0, 0.0, 0.0, 0.0}) {
    return Issue("intrinsics", "not used by model scaramuzza (use center and poly)");
  }
  if (!spec.distortion.empty()) {
    return Issue("distortion", "not used by model scaramuzza (use poly)");
  }
  if (spec.poly.empty() || spec.poly.size() > kMaxPolySize) {
    return Issue("poly", "expected 1 to " + std::to_string(kMaxPolySize) +
                             " coefficients a0..aN (got " + std::to_string(spec.poly.size()) + ")");
  }
  if (!AllFinite(spec.poly)) return Issue("poly", "values must be finite");
  if (!(spec.poly[0] < 0.0)) {
    return Issue("poly",
                 "a0 must be < 0 (OCamCalib convention: bearing (m, -F(rho)), "
                 "got a0 = " +
                     Str(spec.poly[0]) + ")");
  }
  if (spec.inverse_poly.size() > kMaxInversePolySize) {
    return Issue("inverse_poly", "expected at most " + std::to_string(kMaxInversePolySize) +
                                     " coefficients (got " +
                                     std::to_string(spec.inverse_poly.size()) + ")");
  }
  if (!AllFinite(spec.inverse_poly)) {
    return Issue("inverse_poly", "values must be finite");
  }
  if (!std::isfinite(spec.center[0]) || !std::isfinite(spec.center[1]) ||
      !InsideImage(spec.center[0], spec.center[1], spec.width, spec.height)) {
    return Issue("center", "(" + Str(spec.center[0]) + ", " + Str(spec.center[1]) +
                               ") is not inside the " + std::to_string(spec.width) + " x " +
                               std::to_string(spec.height) + " image");
  }
  const auto& a = spec.affine;
  if (!std::isfinite(a[0]) || !std::isfinite(a[1]) || !std::isfinite(a[2]) ||
      !(a[0] - a[1] * a[2] > 0.0)) {
    return Issue("affine", "[c, d, e] must be finite with c - d e > 0 (got [" + Str(a[0]) + ", " +
                               Str(a[1]) + ", " + Str(a[2]) + "])");
  }
  return Status::Ok();
}

// Builds the model of a structurally valid spec, or says why it cannot.
Expected<std::unique_ptr<CameraModel>> Build(const CameraSpec& spec) {
  switch (spec.model) {
    case CameraSpec::Model::kPinhole:
      return internal::BuildPinholeCamera(spec);
    case CameraSpec::Model::kFisheye:
      return internal::BuildFisheyeCamera(spec);
    case CameraSpec::Model::kScaramuzza:
      return internal::BuildScaramuzzaCamera(spec);
  }
  return Issue("model", "unknown model");
}

}  // namespace

std::string_view ModelName(CameraSpec::Model model) {
  switch (model) {
    case CameraSpec::Model::kPinhole:
      return "pinhole";
    case CameraSpec::Model::kFisheye:
      return "fisheye";
    case CameraSpec::Model::kScaramuzza:
      return "scaramuzza";
  }
  return "unknown";
}

std::optional<CameraSpec::Model> ModelFromName(std::string_view name) {
  if (name == "pinhole") return CameraSpec::Model::kPinhole;
  if (name == "fisheye") return CameraSpec::Model::kFisheye;
  if (name == "scaramuzza") return CameraSpec::Model::kScaramuzza;
  return std::nullopt;
}

Status CameraSpec::Check() const {
  if (Status status = CheckStructure(*this); !status.ok()) return status;
  return Build(*this).status();
}

Expected<std::unique_ptr<CameraModel>> MakeCameraModel(const CameraSpec& spec) {
  if (Status status = CheckStructure(spec); !status.ok()) return status;
  Expected<std::unique_ptr<CameraModel>> model = Build(spec);
  if (!model.ok()) return model;
  (*model)->set_rolling_shutter_s(spec.rolling_shutter_s);
  ModuleLogger("vo")->debug("camera '{}': {} {}x{}, max field angle {:.3f} deg, {:.4f} deg/px",
                            spec.name, ModelName(spec.model), spec.width, spec.height,
                            (*model)->MaxFieldAngleDeg(),
                            (*model)->PixelAngle() * internal::kRadToDeg);
  return model;
}

Expected<CameraSpec> ScaramuzzaSpecForEquidistant(const std::string& name, int width, int height,
                                                  double focal_px, double cx, double cy,
                                                  double max_field_angle_deg) {
  const std::string prefix = "equidistant scaramuzza spec '" + name + "': ";
  if (!(focal_px > 0.0 && std::isfinite(focal_px))) {
    return Error{prefix + "focal_px must be > 0 (got " + Str(focal_px) + ")"};
  }
  if (!(width > 0 && height > 0) || !InsideImage(cx, cy, width, height)) {
    return Error{prefix + "centre (" + Str(cx) + ", " + Str(cy) + ") is not inside a " +
                 std::to_string(width) + " x " + std::to_string(height) + " image"};
  }
  if (!(max_field_angle_deg > 0.0 && max_field_angle_deg <= 140.0)) {
    return Error{prefix + "max_field_angle_deg must be in (0, 140] (got " +
                 Str(max_field_angle_deg) + ")"};
  }
  // Ideal lens: theta = rho / f, so the bearing of radius rho is (rho, -F) with
  // -F(rho) = rho cot(rho / f) = f P(t), P(t) = t cot(t), t = rho / f. P is even with P(0) = 1:
  // fit P(t) - 1 = sum_{j>=1} c_j t^(2j) on [0, t_fit], weighted by the sensitivity of the field
  // angle to P, d theta / d P = sin(t)^2 / t, so that the residual is an angle error.
  const double t_max = max_field_angle_deg * internal::kDegToRad;
  const double t_fit =
      std::min(t_max + 2.0 * internal::kDegToRad, 0.5 * (t_max + std::numbers::pi));
  constexpr int kSamples = 800;
  std::vector<double> best_c;
  double best_error_px = std::numeric_limits<double>::infinity();
  for (int terms = 2; terms <= 10; ++terms) {  // poly degree <= 20
    Eigen::MatrixXd basis(kSamples, terms);
    Eigen::VectorXd target(kSamples);
    for (int i = 0; i < kSamples; ++i) {
      const double t = t_fit * (i + 1) / kSamples;
      const double weight = std::sin(t) * std::sin(t) / t;
      double power = t * t;
      for (int j = 0; j < terms; ++j, power *= t * t) basis(i, j) = weight * power;
      target[i] = weight * (t / std::tan(t) - 1.0);
    }
    // Scale the columns for conditioning.
    Eigen::VectorXd scale = basis.colwise().norm().transpose();
    for (int j = 0; j < terms; ++j) basis.col(j) /= scale[j];
    Eigen::VectorXd c = basis.colPivHouseholderQr().solve(target);
    for (int j = 0; j < terms; ++j) c[j] /= scale[j];
    // Pixel radius error: f |theta_model(t) - t| over [0, t_max].
    double error_px = 0.0;
    for (int i = 0; i <= 2000; ++i) {
      const double t = t_max * i / 2000;
      double p = 1.0;
      double power = t * t;
      for (int j = 0; j < terms; ++j, power *= t * t) p += c[j] * power;
      error_px = std::max(error_px, focal_px * std::abs(std::atan2(t, p) - t));
    }
    if (error_px < best_error_px) {
      best_error_px = error_px;
      best_c.assign(c.data(), c.data() + terms);
    }
    if (best_error_px <= 1e-4) break;  // margin below the promised 1e-3 px
  }
  if (!(best_error_px <= 1e-3)) {
    return Error{prefix + "the polynomial fit misses the equidistant lens by " +
                 Str(best_error_px) + " px"};
  }
  CameraSpec spec;
  spec.name = name;
  spec.model = CameraSpec::Model::kScaramuzza;
  spec.width = width;
  spec.height = height;
  spec.center = {cx, cy};
  spec.max_field_angle_deg = max_field_angle_deg;
  // F(rho) = -f P(rho / f): a_{2j} = -f c_j / f^(2j), odd coefficients 0.
  spec.poly.assign(2 * best_c.size() + 1, 0.0);
  spec.poly[0] = -focal_px;
  double f_power = focal_px;
  for (size_t j = 0; j < best_c.size(); ++j) {
    f_power /= focal_px * focal_px;
    spec.poly[2 * (j + 1)] = -best_c[j] * f_power;
  }
  if (Status status = spec.Check(); !status.ok()) return Error{prefix + status.message()};
  return spec;
}

}  // namespace rigcal::camera
