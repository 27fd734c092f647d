// SPDX-License-Identifier: Apache-2.0
// Scaramuzza polynomial omnidirectional camera (thesis 3.2.2, OCamCalib). Conventions in
// rigcal/camera/camera_spec.h. `poly` defines the model (unprojection is closed-form); projection
// inverts it exactly by Newton's method started from `inverse_poly`.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "camera_models.h"

namespace rigcal::camera::internal {
namespace {

constexpr double kScaramuzzaMaxAutomaticFieldAngleDeg = 179.0;
constexpr double kScanStepPx = 0.25;             // radius step when scanning the polynomial
constexpr double kInversePolyTolerancePx = 1.0;  // a given inverse_poly must be this close
constexpr double kFitTolerancePx = 0.01;         // a fitted inverse_poly aims at this
// Newton on the radius stops after a step below this; the error left is ~1e-15 px.
constexpr double kNewtonTolerancePx = 1e-7;
constexpr double kBracketTolerancePx = 1e-12;

class ScaramuzzaCamera final : public CameraModel {
 public:
  explicit ScaramuzzaCamera(const CameraSpec& spec)
      : CameraModel(spec.width, spec.height),
        poly_(spec.poly),
        inverse_poly_(spec.inverse_poly),
        cx_(spec.center[0]),
        cy_(spec.center[1]),
        c_(spec.affine[0]),
        d_(spec.affine[1]),
        e_(spec.affine[2]) {
    // pixel - center = A m with A = [1 e; d c].
    const double inv_det = 1.0 / (c_ - d_ * e_);
    a_inv_ << c_ * inv_det, -e_ * inv_det, -d_ * inv_det, inv_det;
  }

  Status Initialise(double max_field_angle_deg);

  std::string type() const override { return "scaramuzza"; }

  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& point,
                                         Eigen::Matrix<double, 2, 3>* jacobian) const override {
    const double x = point.x();
    const double y = point.y();
    const double z = point.z();
    const double n2 = x * x + y * y;
    const double n = std::sqrt(n2);
    const double theta = std::atan2(n, z);
    if (!(theta <= theta_max_)) return std::nullopt;
    Eigen::Matrix<double, 2, 3> d_m;
    Eigen::Vector2d m;
    if (n <= 1e-12 * z) {
      // On the axis: rho = -a0 n / z to first order.
      if (!(z > 0.0)) return std::nullopt;  // the origin
      const double s = -poly_[0] / z;
      m = Eigen::Vector2d(s * x, s * y);
      d_m << s, 0.0, -s * x / z, 0.0, s, -s * y / z;
    } else {
      const double norm = std::sqrt(n2 + z * z);
      const double rho = SolveRho(n / norm, z / norm, theta);
      // G(rho, p) = rho z + F(rho) n = 0 defines rho(p); g = dG / drho.
      double f_slope = 0.0;
      const double f = Polynomial(poly_, rho, &f_slope);
      const double g = z + f_slope * n;
      const double s = rho / n;  // m = s (x, y)
      m = Eigen::Vector2d(s * x, s * y);
      if (jacobian) {
        // d rho / d p = -(F x / n, F y / n, rho) / g, s = rho / n:
        // d s / d(x, y) = a (x, y) with a = -(F / g + s) / n^2, d s / d z = -s / g.
        const double a = -(f / g + s) / n2;
        const double b = -s / g;
        d_m << s + a * x * x, a * x * y, b * x, a * x * y, s + a * y * y, b * y;
      }
    }
    if (jacobian) {
      jacobian->row(0) = d_m.row(0) + e_ * d_m.row(1);
      jacobian->row(1) = d_ * d_m.row(0) + c_ * d_m.row(1);
    }
    return Eigen::Vector2d(cx_ + m.x() + e_ * m.y(), cy_ + d_ * m.x() + c_ * m.y());
  }

  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& pixel,
                                           Eigen::Matrix<double, 3, 2>* jacobian) const override {
    const Eigen::Vector2d m = a_inv_ * Eigen::Vector2d(pixel.x() - cx_, pixel.y() - cy_);
    const double rho = m.norm();
    if (!(rho <= rho_max_ * (1.0 + 1e-12))) return std::nullopt;
    double f_slope = 0.0;
    const double f = Polynomial(poly_, rho, &f_slope);
    const Eigen::Vector3d ray(m.x(), m.y(), -f);
    const double inv_norm = 1.0 / ray.norm();
    const Eigen::Vector3d bearing = ray * inv_norm;
    if (jacobian) {
      Eigen::Matrix<double, 3, 2> d_ray_d_m;
      const double k = rho > 0.0 ? -f_slope / rho : 0.0;  // d(-F)/dm = -F' m^T / rho
      d_ray_d_m << 1.0, 0.0, 0.0, 1.0, k * m.x(), k * m.y();
      *jacobian = (Eigen::Matrix3d::Identity() - bearing * bearing.transpose()) * inv_norm *
                  d_ray_d_m * a_inv_;
    }
    return bearing;
  }

  double MaxFieldAngleDeg() const override { return theta_max_ * kRadToDeg; }
  double PixelAngle() const override { return pixel_angle_; }
  std::unique_ptr<CameraModel> Clone() const override {
    return std::make_unique<ScaramuzzaCamera>(*this);
  }

 private:
  // Field angle of the sensor-plane radius rho: atan2(rho, -F(rho)); optionally its derivative
  // (rho F' - F) / (rho^2 + F^2).
  double FieldAngle(double rho, double* slope = nullptr) const {
    double f_slope = 0.0;
    const double f = Polynomial(poly_, rho, &f_slope);
    if (slope) *slope = (rho * f_slope - f) / (rho * rho + f * f);
    return std::atan2(rho, -f);
  }

  // The radius in [0, rho_max_] whose field angle is theta (sin and cos given): the root of
  // h(rho) = rho cos(theta) + F(rho) sin(theta) = |(rho, F)| sin(FieldAngle(rho) - theta),
  // increasing through its root. Starts from inverse_poly (OCamCalib: phi = theta - pi/2).
  double SolveRho(double sin_theta, double cos_theta, double theta) const {
    double guess;
    if (sin_theta < 0.01 * cos_theta) {
      // Near the axis: rho ~ -a0 tan(theta) / (1 + a1 tan(theta)).
      const double tan_theta = sin_theta / cos_theta;
      const double a1 = poly_.size() > 1 ? poly_[1] : 0.0;
      guess = -poly_[0] * tan_theta / (1.0 + a1 * tan_theta);
    } else {
      guess = Polynomial(inverse_poly_, theta - std::numbers::pi / 2);
    }
    return SolveIncreasing(
        [this, sin_theta, cos_theta](double rho, double* slope) {
          double f_slope = 0.0;
          const double f = Polynomial(poly_, rho, &f_slope);
          *slope = cos_theta + f_slope * sin_theta;
          return rho * cos_theta + f * sin_theta;
        },
        guess, 0.0, rho_max_, kNewtonTolerancePx, kBracketTolerancePx);
  }

  // The exact radius of field angle theta, for fitting and checking inverse_poly.
  double ExactRho(double theta) const { return SolveRho(std::sin(theta), std::cos(theta), theta); }

  // Largest deviation (px) of inverse_poly from the exact radius over [0, theta_max_], and the
  // field angle where it occurs.
  double InversePolyError(const std::vector<double>& inverse_poly, double* at_theta) const {
    double worst = 0.0;
    constexpr int kSamples = 400;
    for (int i = 0; i <= kSamples; ++i) {
      const double theta = theta_max_ * i / kSamples;
      const double error =
          std::abs(Polynomial(inverse_poly, theta - std::numbers::pi / 2) - ExactRho(theta));
      if (!(error <= worst)) {
        worst = error;
        *at_theta = theta;
      }
    }
    return worst;
  }

  // Least-squares inverse polynomial rho(phi), phi = theta - pi/2, of the lowest degree that
  // meets kFitTolerancePx (or the best one found up to degree 20).
  std::vector<double> FitInversePoly() const;

  std::vector<double> poly_;
  std::vector<double> inverse_poly_;
  double cx_, cy_;
  double c_, d_, e_;
  Eigen::Matrix2d a_inv_;
  double rho_max_ = 0.0;    // sensor-plane radius of theta_max_
  double theta_max_ = 0.0;  // radians
  double pixel_angle_ = 0.0;
};

std::vector<double> ScaramuzzaCamera::FitInversePoly() const {
  constexpr int kSamples = 600;
  Eigen::VectorXd phi(kSamples + 1);
  Eigen::VectorXd rho(kSamples + 1);
  for (int i = 0; i <= kSamples; ++i) {
    const double theta = theta_max_ * i / kSamples;
    phi[i] = theta - std::numbers::pi / 2;
    rho[i] = ExactRho(theta);
  }
  std::vector<double> best;
  double best_error = std::numeric_limits<double>::infinity();
  for (int degree = 2; degree <= 20; ++degree) {
    Eigen::MatrixXd basis(kSamples + 1, degree + 1);
    for (int i = 0; i <= kSamples; ++i) {
      double power = 1.0;
      for (int j = 0; j <= degree; ++j, power *= phi[i]) basis(i, j) = power;
    }
    const Eigen::VectorXd coefficients = basis.colPivHouseholderQr().solve(rho);
    std::vector<double> candidate(coefficients.data(), coefficients.data() + coefficients.size());
    double at_theta = 0.0;
    const double error = InversePolyError(candidate, &at_theta);
    if (error < best_error) {
      best_error = error;
      best = std::move(candidate);
    }
    if (best_error <= kFitTolerancePx) break;
  }
  return best;
}

Status ScaramuzzaCamera::Initialise(double max_field_angle_deg) {
  const bool automatic = max_field_angle_deg == 0.0;
  const double theta_cap =
      (automatic ? kScaramuzzaMaxAutomaticFieldAngleDeg : max_field_angle_deg) * kDegToRad;
  // The farthest image corner in the sensor plane (|m| is convex in the pixel).
  double rho_corner = 0.0;
  for (const double u : {-0.5, width() - 0.5}) {
    for (const double v : {-0.5, height() - 0.5}) {
      rho_corner = std::max(rho_corner, (a_inv_ * Eigen::Vector2d(u - cx_, v - cy_)).norm());
    }
  }
  const double rho_limit = rho_corner + 100.0 * (width() + height());

  // Scan outwards while the field angle increases, up to theta_cap (or the farthest corner).
  double previous_rho = 0.0;
  double previous_theta = 0.0;
  for (int k = 1;; ++k) {
    double rho = k * kScanStepPx;
    if (automatic && rho >= rho_corner) rho = rho_corner;
    double slope = 0.0;
    const double theta = FieldAngle(rho, &slope);
    if (!(slope > 0.0) || !(theta > previous_theta)) {
      if (!automatic) {
        std::ostringstream what;
        what << "the field angle of poly stops increasing at " << previous_theta * kRadToDeg
             << " deg (radius " << previous_rho << " px) before max_field_angle_deg";
        return Issue("max_field_angle_deg", what.str());
      }
      rho_max_ = previous_rho;
      break;
    }
    if (theta >= theta_cap) {
      rho_max_ = SolveIncreasing(
          [this, theta_cap](double r, double* s) { return FieldAngle(r, s) - theta_cap; }, rho,
          previous_rho, rho, 1e-12, 1e-13);  // once per model: to the rounding level
      break;
    }
    if (automatic && rho >= rho_corner) {
      rho_max_ = rho;
      break;
    }
    if (rho > rho_limit) {
      std::ostringstream what;
      what << "poly reaches only " << theta * kRadToDeg << " deg at a radius of " << rho
           << " px; max_field_angle_deg is beyond the lens";
      return Issue("max_field_angle_deg", what.str());
    }
    previous_rho = rho;
    previous_theta = theta;
  }
  if (!(rho_max_ > 0.0)) {
    return Issue("poly", "the field angle does not increase from the centre");
  }
  // A given limit is kept exactly (Project accepts exactly max_field_angle_deg).
  theta_max_ = automatic ? FieldAngle(rho_max_) : theta_cap;

  if (inverse_poly_.empty()) {
    // SolveRho falls back to bisection until the fit exists; fine for sampling.
    inverse_poly_ = FitInversePoly();
  } else {
    double at_theta = 0.0;
    const double error = InversePolyError(inverse_poly_, &at_theta);
    if (!(error <= kInversePolyTolerancePx)) {
      std::ostringstream what;
      what << "does not invert poly: off by " << error << " px at a field angle of "
           << at_theta * kRadToDeg
           << " deg (OCamCalib convention: rho(theta - 90 deg), radians; omit it to have it "
              "fitted)";
      return Issue("inverse_poly", what.str());
    }
  }

  if (!PixelAngleAt(*this, Eigen::Vector2d(cx_, cy_), &pixel_angle_)) {
    return Issue("center", "cannot unproject the centre");
  }
  return Status::Ok();
}

}  // namespace

Expected<std::unique_ptr<CameraModel>> BuildScaramuzzaCamera(const CameraSpec& spec) {
  auto camera = std::make_unique<ScaramuzzaCamera>(spec);
  if (Status status = camera->Initialise(spec.max_field_angle_deg); !status.ok()) return status;
  return std::unique_ptr<CameraModel>(std::move(camera));
}

}  // namespace rigcal::camera::internal
