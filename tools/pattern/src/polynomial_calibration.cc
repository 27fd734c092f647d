// SPDX-License-Identifier: Apache-2.0
// Polynomial omnidirectional intrinsics: linear initialisation, then Ceres.
#include "polynomial_calibration.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include "planar_pose.h"
#include "rigcal/base/logging.h"

namespace rigcal::pattern::internal {
namespace {

// Degrees tried, chosen by the data (BIC): `terms` coefficients a0, a2, ..., a_terms of
// F(rho) (a1 = 0), degree 3 (a0, a2, a3) to 7.
constexpr int kMinTerms = 3;
constexpr int kMaxTerms = 7;  // FitWithTerms instantiates Refine<3> .. Refine<7>

double ValueOf(double x) { return x; }
template <typename T, int N>
double ValueOf(const ceres::Jet<T, N>& x) {
  return x.a;
}

// F(r) = a0 + a2 r^2 + ... + a_terms r^terms and F'(r), in normalised radius r = rho / s.
template <typename T, typename R>
T PolyValue(const T* a, int terms, const R& r) {
  T tail = a[terms - 1];
  for (int k = terms - 2; k >= 1; --k) tail = a[k] + r * tail;
  return a[0] + r * r * tail;
}
template <typename T, typename R>
T PolyDerivative(const T* a, int terms, const R& r) {
  T sum = a[terms - 1] * static_cast<double>(terms);
  for (int k = terms - 2; k >= 1; --k) sum = a[k] * static_cast<double>(k + 1) + r * sum;
  return r * sum;
}

// The smallest r >= 0 with r z + F(r) rxy = 0 (a bearing's normalised radius), by a scan for the
// first sign change up to r_max and bisection; nullopt when there is none.
std::optional<double> RadiusOfBearing(const double* a, int terms, double z, double rxy) {
  const double norm = std::hypot(z, rxy);
  if (!(norm > 0.0)) return std::nullopt;
  const double c = z / norm;
  const double s = rxy / norm;
  if (s <= 0.0) return 0.0;
  const auto h = [&](double r) { return r * c + PolyValue(a, terms, r) * s; };
  constexpr double kMaxRadius = 4.0;  // twice the larger image side
  constexpr int kSteps = 400;
  double lo = 0.0;
  double h_lo = h(lo);
  if (h_lo >= 0.0) return std::nullopt;  // a0 >= 0: no forward-looking camera
  for (int i = 1; i <= kSteps; ++i) {
    const double hi = kMaxRadius * i / kSteps;
    const double h_hi = h(hi);
    if (h_hi >= 0.0) {
      double left = lo;
      double right = hi;
      for (int k = 0; k < 60; ++k) {
        const double mid = 0.5 * (left + right);
        (h(mid) < 0.0 ? left : right) = mid;
      }
      return 0.5 * (left + right);
    }
    lo = hi;
  }
  return std::nullopt;
}

// Pixel of a camera-frame point: intr = [cx, cy, c, d] (e = 0), a = normalised polynomial.
template <typename T>
bool ProjectPolynomial(const T* intr, const T* a, int terms, double scale, const T* P, T* uv) {
  const T rxy = ceres::sqrt(P[0] * P[0] + P[1] * P[1] + 1e-300);
  std::array<double, kMaxTerms> a_value{};
  for (int k = 0; k < terms; ++k) a_value[static_cast<size_t>(k)] = ValueOf(a[k]);
  const std::optional<double> r0 =
      RadiusOfBearing(a_value.data(), terms, ValueOf(P[2]), ValueOf(rxy));
  if (!r0) return false;
  // One Newton step in T: the value stays r0, the derivatives become those of the root.
  const T h = *r0 * P[2] + PolyValue(a, terms, *r0) * rxy;
  const T dh = P[2] + PolyDerivative(a, terms, *r0) * rxy;
  const T r = *r0 - h / dh;
  const T mx = scale * r * P[0] / rxy;
  const T my = scale * r * P[1] / rxy;
  uv[0] = intr[0] + mx;
  uv[1] = intr[1] + intr[3] * mx + intr[2] * my;
  return true;
}

template <int kTerms>
struct CornerResidual {
  Eigen::Vector2d pixel;
  Eigen::Vector2d target;  // (X, Y) on the z = 0 plane
  double scale;

  template <typename T>
  bool operator()(const T* intr, const T* a, const T* angle_axis, const T* t, T* residual) const {
    const T X[3] = {T(target.x()), T(target.y()), T(0.0)};
    T P[3];
    ceres::AngleAxisRotatePoint(angle_axis, X, P);
    for (int k = 0; k < 3; ++k) P[k] += t[k];
    T uv[2];
    if (!ProjectPolynomial(intr, a, kTerms, scale, P, uv)) return false;
    residual[0] = uv[0] - pixel.x();
    residual[1] = uv[1] - pixel.y();
    return true;
  }
};

struct ViewPose {
  Eigen::Matrix3d R;  // camera from target
  Eigen::Vector3d t;
};

// First two rows of [r1 r2 t] of one view (up to scale) and the two completions of r31, r32.
std::array<ViewPose, 2> PartialPoses(const TargetView& view, const Eigen::Vector2d& centre,
                                     double scale) {
  const Eigen::Index n = static_cast<Eigen::Index>(view.pixels.size());
  Eigen::MatrixXd M(n, 6);
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Vector2d m = (view.pixels[static_cast<size_t>(i)] - centre) / scale;
    const double X = view.target_points[static_cast<size_t>(i)].x();
    const double Y = view.target_points[static_cast<size_t>(i)].y();
    M.row(i) << m.y() * X, m.y() * Y, -m.x() * X, -m.x() * Y, m.y(), -m.x();
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(M, Eigen::ComputeFullV);
  const Eigen::VectorXd h = svd.matrixV().col(5);
  const double r11 = h(0), r12 = h(1), r21 = h(2), r22 = h(3);
  const double B = -(r11 * r12 + r21 * r22);                           // r31 r32
  const double C = (r11 * r11 + r21 * r21) - (r12 * r12 + r22 * r22);  // r32^2 - r31^2
  const double r32_sq = 0.5 * (C + std::sqrt(C * C + 4.0 * B * B));
  std::array<ViewPose, 2> out;
  for (int sign = 0; sign < 2; ++sign) {
    const double r32 = (sign == 0 ? 1.0 : -1.0) * std::sqrt(std::max(r32_sq, 0.0));
    const double r31_abs = std::sqrt(std::max(r32_sq - C, 0.0));
    const double r31 = (B * r32 < 0.0 ? -1.0 : 1.0) * r31_abs;
    const double lambda = 1.0 / std::sqrt(r11 * r11 + r21 * r21 + r31 * r31);
    ViewPose& p = out[static_cast<size_t>(sign)];
    p.R.col(0) = lambda * Eigen::Vector3d(r11, r21, r31);
    p.R.col(1) = lambda * Eigen::Vector3d(r12, r22, r32);
    p.R.col(2) = p.R.col(0).cross(p.R.col(1));
    p.t = lambda * Eigen::Vector3d(h(4), h(5), 0.0);
  }
  return out;
}

// Least squares for the normalised polynomial (`terms` coefficients: a0, a2, a3, ...) and
// every view's t3, given the views' partial poses; returns the residual norm.
double SolvePolynomialAndDepths(const CameraViews& views, const std::vector<size_t>& indices,
                                const std::vector<ViewPose>& poses, const Eigen::Vector2d& centre,
                                double scale, int terms, Eigen::VectorXd* a,
                                Eigen::VectorXd* depths) {
  Eigen::Index rows = 0;
  for (size_t i : indices) rows += static_cast<Eigen::Index>(2 * views.views[i].pixels.size());
  const auto n_views = static_cast<Eigen::Index>(indices.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, terms + n_views);
  Eigen::VectorXd b(rows);
  Eigen::Index row = 0;
  for (Eigen::Index v = 0; v < n_views; ++v) {
    const TargetView& view = views.views[indices[static_cast<size_t>(v)]];
    const ViewPose& pose = poses[static_cast<size_t>(v)];
    for (size_t j = 0; j < view.pixels.size(); ++j) {
      const Eigen::Vector2d m = (view.pixels[j] - centre) / scale;
      const Eigen::Vector3d P0 = pose.R.col(0) * view.target_points[j].x() +
                                 pose.R.col(1) * view.target_points[j].y() + pose.t;  // t3 = 0
      const double rho = m.norm();
      // P x b = 0 with b = (mx, my, -F): y and x components.
      double power = 1.0;  // rho^0, rho^2, rho^3, ...
      for (int k = 0; k < terms; ++k) {
        power = k == 0 ? 1.0 : (k == 1 ? rho * rho : power * rho);
        A(row, k) = P0.y() * power;
        A(row + 1, k) = P0.x() * power;
      }
      A(row, terms + v) = m.y();
      A(row + 1, terms + v) = m.x();
      b(row) = -P0.z() * m.y();
      b(row + 1) = -P0.z() * m.x();
      row += 2;
    }
  }
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  *a = x.head(terms);
  *depths = x.tail(n_views);
  return (A * x - b).norm();
}

struct PolynomialFit {
  std::array<double, 4> intr{};       // cx, cy, c, d
  std::array<double, kMaxTerms> a{};  // normalised a0, a2, ...
  double sum_sq = 0.0;                // sum of squared corner errors [px^2]
  size_t corners = 0;
};

template <int kTerms>
Expected<PolynomialFit> Refine(const CameraViews& views, const std::vector<size_t>& indices,
                               std::vector<std::array<double, 6>> pose_blocks,
                               const Eigen::Vector2d& centre, double scale,
                               const Eigen::VectorXd& a_init) {
  PolynomialFit fit;
  fit.intr = {centre.x(), centre.y(), 1.0, 0.0};
  for (int k = 0; k < kTerms; ++k) fit.a[static_cast<size_t>(k)] = a_init(k);
  ceres::Problem problem;
  for (size_t v = 0; v < indices.size(); ++v) {
    const TargetView& view = views.views[indices[v]];
    for (size_t j = 0; j < view.pixels.size(); ++j) {
      auto* cost = new ceres::AutoDiffCostFunction<CornerResidual<kTerms>, 2, 4, kTerms, 3, 3>(
          new CornerResidual<kTerms>{view.pixels[j], view.target_points[j].head<2>(), scale});
      problem.AddResidualBlock(cost, nullptr, fit.intr.data(), fit.a.data(), pose_blocks[v].data(),
                               pose_blocks[v].data() + 3);
      ++fit.corners;
    }
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 200;
  options.function_tolerance = 1e-12;
  options.parameter_tolerance = 1e-12;
  options.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (summary.termination_type == ceres::FAILURE || !std::isfinite(summary.final_cost)) {
    return Error{views.camera + ": the polynomial model's refinement failed (degree " +
                 std::to_string(kTerms) + "): " + summary.message};
  }
  fit.sum_sq = 2.0 * summary.final_cost;
  return fit;
}

// The polynomial with `terms` coefficients and every view's depth from the linear system, each
// view turned to face the camera, then refined.
Expected<PolynomialFit> FitWithTerms(const CameraViews& views, const std::vector<size_t>& indices,
                                     std::vector<ViewPose> poses, const Eigen::Vector2d& centre,
                                     double scale, int terms) {
  Eigen::VectorXd a;
  Eigen::VectorXd depths;
  SolvePolynomialAndDepths(views, indices, poses, centre, scale, terms, &a, &depths);
  if (!(a(0) < 0.0)) {
    return Error{views.camera +
                 ": the linear initialisation of the polynomial model found no camera "
                 "looking at the target (a0 = " +
                 std::to_string(a(0) * scale) + "); check the target's corner order"};
  }
  std::vector<std::array<double, 6>> pose_blocks(indices.size());
  for (size_t v = 0; v < indices.size(); ++v) {
    ViewPose& pose = poses[v];
    pose.t.z() = depths(static_cast<Eigen::Index>(v));
    const TargetView& view = views.views[indices[v]];
    double facing = 0.0;  // the corners' points along their bearings
    for (size_t j = 0; j < view.pixels.size(); ++j) {
      const Eigen::Vector2d m = (view.pixels[j] - centre) / scale;
      const Eigen::Vector3d bearing(m.x(), m.y(), -PolyValue(a.data(), terms, m.norm()));
      facing += bearing.dot(pose.R * view.target_points[j] + pose.t);
    }
    if (facing < 0.0) {  // the mirror solution: rotate by pi about r3
      pose.R.col(0) = -pose.R.col(0);
      pose.R.col(1) = -pose.R.col(1);
      pose.t = -pose.t;
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> polar(pose.R,
                                                  Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d R = polar.matrixU() * polar.matrixV().transpose();
    if (R.determinant() < 0.0) R = -R;
    ceres::RotationMatrixToAngleAxis(R.data(), pose_blocks[v].data());
    for (Eigen::Index k = 0; k < 3; ++k) pose_blocks[v][static_cast<size_t>(k) + 3] = pose.t(k);
  }
  switch (terms) {
    case 3:
      return Refine<3>(views, indices, std::move(pose_blocks), centre, scale, a);
    case 4:
      return Refine<4>(views, indices, std::move(pose_blocks), centre, scale, a);
    case 5:
      return Refine<5>(views, indices, std::move(pose_blocks), centre, scale, a);
    case 6:
      return Refine<6>(views, indices, std::move(pose_blocks), centre, scale, a);
    default:
      return Refine<kMaxTerms>(views, indices, std::move(pose_blocks), centre, scale, a);
  }
}

}  // namespace

Status CalibratePolynomial(const CameraViews& views, const std::vector<size_t>& indices,
                           camera::CameraSpec* spec, double* rms_px) {
  const auto log = ModuleLogger("target");
  const std::string& name = views.camera;
  if (indices.size() < 3) return Error{name + ": the polynomial model needs at least 3 views"};
  for (size_t i : indices) {
    const TargetView& view = views.views[i];
    if (view.pixels.size() < 6) {
      return Error{name + ": view " + view.file + " has fewer than 6 corners"};
    }
    if (!OnTargetPlane(view)) {
      return Error{name + ": view " + view.file + ": the target is not on its z = 0 plane"};
    }
  }
  const double scale = 0.5 * std::max(views.width, views.height);
  const Eigen::Vector2d centre(0.5 * (views.width - 1), 0.5 * (views.height - 1));

  // Per view the completion of r31, r32 that fits it better (a0, a2 and its t3 alone).
  std::vector<ViewPose> poses;
  for (size_t i : indices) {
    const std::array<ViewPose, 2> candidates = PartialPoses(views.views[i], centre, scale);
    double best = std::numeric_limits<double>::infinity();
    ViewPose chosen = candidates[0];
    for (ViewPose candidate : candidates) {
      Eigen::VectorXd a;
      Eigen::VectorXd depth;
      const double residual =
          SolvePolynomialAndDepths(views, {i}, {candidate}, centre, scale, 2, &a, &depth);
      if (a(0) > 0.0) {
        // The SVD's sign of the first two rows: the other one makes F(0) < 0 for this view,
        // so that all views agree on the sign of F.
        candidate.R.topRows<2>() *= -1.0;
        candidate.R.col(2) = candidate.R.col(0).cross(candidate.R.col(1));
        candidate.t.head<2>() *= -1.0;
      }
      if (residual < best) {
        best = residual;
        chosen = candidate;
      }
    }
    poses.push_back(chosen);
  }
  // Every degree from its own linear start; the one with the smallest BIC whose camera is valid.
  const Status no_fit = Error{name + ": the polynomial model's refinement failed"};
  Status first_error = no_fit;
  double best_bic = std::numeric_limits<double>::infinity();
  for (int terms = kMinTerms; terms <= kMaxTerms; ++terms) {
    Expected<PolynomialFit> fit = FitWithTerms(views, indices, poses, centre, scale, terms);
    if (!fit) {
      if (first_error.message() == no_fit.message()) first_error = Error{fit.error()};
      continue;
    }
    camera::CameraSpec candidate = *spec;
    candidate.model = camera::CameraSpec::Model::kScaramuzza;
    candidate.intrinsics = {0.0, 0.0, 0.0, 0.0};
    candidate.distortion.clear();
    candidate.poly.assign(static_cast<size_t>(terms) + 1, 0.0);  // a1 = 0
    double unit = scale;                                         // a_k = a~_k s^(1 - k)
    for (int k = 0; k < terms; ++k) {
      const int power = k == 0 ? 0 : k + 1;
      if (k == 1) unit = 1.0 / scale;
      if (k > 1) unit /= scale;
      candidate.poly[static_cast<size_t>(power)] = fit->a[static_cast<size_t>(k)] * unit;
    }
    candidate.inverse_poly.clear();
    candidate.center = {fit->intr[0], fit->intr[1]};
    candidate.affine = {fit->intr[2], fit->intr[3], 0.0};
    if (Status s = candidate.Check(); !s.ok()) {
      log->debug("{}: degree {}: not a valid camera ({})", name, terms, s.message());
      if (first_error.message() == no_fit.message()) {
        first_error =
            Error{name + ": the calibrated polynomial model is not a valid camera: " + s.message()};
      }
      continue;
    }
    // BIC over the 2N corner coordinates; the poses and the centre are common to all degrees.
    const double n = 2.0 * static_cast<double>(fit->corners);
    const double bic = n * std::log(fit->sum_sq / n) + terms * std::log(n);
    log->debug("{}: degree {}: RMS {:.4f} px, BIC {:.1f}", name, terms,
               std::sqrt(fit->sum_sq / static_cast<double>(fit->corners)), bic);
    if (bic < best_bic) {
      best_bic = bic;
      *spec = candidate;
      *rms_px = std::sqrt(fit->sum_sq / static_cast<double>(fit->corners));
    }
  }
  if (!std::isfinite(best_bic)) return first_error;
  log->info("{}: polynomial of degree {} (chosen by BIC from {} to {}), RMS {:.3f} px", name,
            spec->poly.size() - 1, kMinTerms, kMaxTerms, *rms_px);
  return {};
}

}  // namespace rigcal::pattern::internal
