// SPDX-License-Identifier: Apache-2.0
#include "absolute_pose.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "ransac_sampling.h"
#include "triangulation.h"

namespace rigcal::vo {
namespace {

// Polynomial in v, coefficients by ascending power (degree <= 4).
using Poly4 = std::array<double, 5>;

Poly4 Mul(const Poly4& a, const Poly4& b) {
  Poly4 out{};
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; i + j < 5; ++j) out[i + j] += a[i] * b[j];
  }
  return out;
}

Poly4 Sub(const Poly4& a, const Poly4& b) {
  Poly4 out;
  for (int i = 0; i < 5; ++i) out[i] = a[i] - b[i];
  return out;
}

Poly4 Scale(const Poly4& a, double s) {
  Poly4 out;
  for (int i = 0; i < 5; ++i) out[i] = a[i] * s;
  return out;
}

double Eval(const Poly4& p, double v) {
  return (((p[4] * v + p[3]) * v + p[2]) * v + p[1]) * v + p[0];
}

// Real roots of a polynomial of degree <= 4 (companion matrix eigenvalues + Newton polish).
std::vector<double> RealRoots(const Poly4& p) {
  int degree = 4;
  const double scale =
      std::max({std::abs(p[0]), std::abs(p[1]), std::abs(p[2]), std::abs(p[3]), std::abs(p[4])});
  if (!(scale > 0.0)) return {};
  while (degree > 0 && std::abs(p[degree]) < 1e-12 * scale) --degree;
  std::vector<double> roots;
  if (degree == 0) return roots;
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (int i = 0; i < degree; ++i) companion(0, i) = -p[degree - 1 - i] / p[degree];
  for (int i = 1; i < degree; ++i) companion(i, i - 1) = 1.0;
  Eigen::EigenSolver<Eigen::MatrixXd> eig(companion, false);
  if (eig.info() != Eigen::Success) return roots;
  Poly4 dp{};
  for (int i = 1; i < 5; ++i) dp[i - 1] = i * p[i];
  for (int i = 0; i < degree; ++i) {
    const std::complex<double> root = eig.eigenvalues()(i);
    if (std::abs(root.imag()) > 1e-6 * (1.0 + std::abs(root.real()))) continue;
    double v = root.real();
    for (int it = 0; it < 3; ++it) {
      const double d = Eval(dp, v);
      if (std::abs(d) < 1e-15) break;
      v -= Eval(p, v) / d;
    }
    roots.push_back(v);
  }
  return roots;
}

// R, C with X_i = R P_i + C for three (or more) point pairs (Kabsch).
CameraPoseRC AlignPoints(const std::array<Eigen::Vector3d, 3>& p_cam,
                         const std::array<Eigen::Vector3d, 3>& x_world) {
  const Eigen::Vector3d p_mean = (p_cam[0] + p_cam[1] + p_cam[2]) / 3.0;
  const Eigen::Vector3d x_mean = (x_world[0] + x_world[1] + x_world[2]) / 3.0;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) h += (p_cam[i] - p_mean) * (x_world[i] - x_mean).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  CameraPoseRC pose;
  pose.R_world_from_cam = svd.matrixV() * d * svd.matrixU().transpose();
  pose.C = x_mean - pose.R_world_from_cam * p_mean;
  return pose;
}

}  // namespace

Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) {
    Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
    r(0, 1) = -w.z();
    r(0, 2) = w.y();
    r(1, 0) = w.z();
    r(1, 2) = -w.x();
    r(2, 0) = -w.y();
    r(2, 1) = w.x();
    return r;
  }
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

Eigen::Matrix<double, 3, 2> TangentBasis(const Eigen::Vector3d& f) {
  const Eigen::Vector3d a =
      std::abs(f.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = (a - a.dot(f) * f).normalized();
  basis.col(1) = f.cross(basis.col(0));
  return basis;
}

std::vector<CameraPoseRC> SolveP3P(const std::array<Eigen::Vector3d, 3>& f,
                                   const std::array<Eigen::Vector3d, 3>& X) {
  std::vector<CameraPoseRC> poses;
  const double a2 = (X[1] - X[2]).squaredNorm();
  const double b2 = (X[0] - X[2]).squaredNorm();
  const double c2 = (X[0] - X[1]).squaredNorm();
  if (a2 < 1e-18 || b2 < 1e-18 || c2 < 1e-18) return poses;
  const double cos_alpha = f[1].dot(f[2]);
  const double cos_beta = f[0].dot(f[2]);
  const double cos_gamma = f[0].dot(f[1]);

  // Depths s1, s2 = u s1, s3 = v s1. With D(v) = 1 + v^2 - 2 v cos(beta), s1^2 = b^2 / D(v):
  //   p(u) = b^2 u^2 - 2 b^2 cos(alpha) v u + b^2 v^2 - a^2 D(v) = 0
  //   q(u) = b^2 u^2 - 2 b^2 cos(gamma) u + b^2 - c^2 D(v) = 0
  // whose resultant in u is a quartic in v.
  const Poly4 d = {1.0, -2.0 * cos_beta, 1.0, 0.0, 0.0};
  const Poly4 p1 = {0.0, -2.0 * b2 * cos_alpha, 0.0, 0.0, 0.0};
  const Poly4 p0 = Sub(Poly4{0.0, 0.0, b2, 0.0, 0.0}, Scale(d, a2));
  const Poly4 q1 = {-2.0 * b2 * cos_gamma, 0.0, 0.0, 0.0, 0.0};
  const Poly4 q0 = Sub(Poly4{b2, 0.0, 0.0, 0.0, 0.0}, Scale(d, c2));
  // Res / b^2 = b^2 (q0 - p0)^2 - (q1 - p1)(p1 q0 - p0 q1).
  const Poly4 dq0 = Sub(q0, p0);
  const Poly4 resultant =
      Sub(Scale(Mul(dq0, dq0), b2), Mul(Sub(q1, p1), Sub(Mul(p1, q0), Mul(p0, q1))));

  for (const double v : RealRoots(resultant)) {
    if (!(v > 0.0)) continue;
    const double p1v = Eval(p1, v);
    const double q1v = Eval(q1, v);
    if (std::abs(p1v - q1v) < 1e-14 * b2) continue;
    const double u = (Eval(q0, v) - Eval(p0, v)) / (p1v - q1v);
    const double dv = Eval(d, v);
    if (!(u > 0.0) || !(dv > 0.0)) continue;
    const double s1 = std::sqrt(b2 / dv);
    const std::array<Eigen::Vector3d, 3> p_cam = {s1 * f[0], u * s1 * f[1], v * s1 * f[2]};
    CameraPoseRC pose = AlignPoints(p_cam, X);
    if (!pose.R_world_from_cam.allFinite() || !pose.C.allFinite()) continue;
    poses.push_back(pose);
  }
  return poses;
}

double AngularResidual(const CameraPoseRC& pose, const Eigen::Vector3d& f,
                       const Eigen::Vector3d& X) {
  return BearingAngle(pose.R_world_from_cam, pose.C, f, X);
}

PnpRansacResult EstimateAbsolutePose(const std::vector<Eigen::Vector3d>& f,
                                     const std::vector<Eigen::Vector3d>& X,
                                     const PnpRansacOptions& options, const CameraPoseRC* prior,
                                     std::mt19937* rng) {
  PnpRansacResult result;
  const int n = static_cast<int>(std::min(f.size(), X.size()));
  if (n < 3 || n < options.min_inliers) return result;
  const double cos_threshold = std::cos(options.max_angle_rad);

  auto count_inliers = [&](const CameraPoseRC& pose, std::vector<char>* mask) {
    const Eigen::Matrix3d rt = pose.R_world_from_cam.transpose();
    int count = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d p = rt * (X[i] - pose.C);
      const double norm = p.norm();
      const bool in = norm > 0.0 && f[i].dot(p) >= cos_threshold * norm;
      if (mask) (*mask)[i] = in;
      count += in;
    }
    return count;
  };

  int best_count = -1;
  CameraPoseRC best;
  int needed = options.max_iterations;
  if (prior != nullptr) {
    best_count = count_inliers(*prior, nullptr);
    best = *prior;
    needed = RansacIterations(static_cast<double>(best_count) / n, 3, options.confidence);
  }
  int iteration = 0;
  std::array<int, 3> sample;
  std::array<Eigen::Vector3d, 3> sf, sx;
  for (; iteration < std::min(needed, options.max_iterations); ++iteration) {
    SampleDistinct(n, &sample, rng);
    for (int k = 0; k < 3; ++k) {
      sf[k] = f[sample[k]];
      sx[k] = X[sample[k]];
    }
    for (const CameraPoseRC& pose : SolveP3P(sf, sx)) {
      const int count = count_inliers(pose, nullptr);
      if (count > best_count) {
        best_count = count;
        best = pose;
        needed = RansacIterations(static_cast<double>(count) / n, 3, options.confidence);
      }
    }
  }
  result.iterations = iteration;
  if (best_count < options.min_inliers) return result;
  result.pose = best;
  result.inliers.assign(n, 0);
  result.num_inliers = count_inliers(best, &result.inliers);
  result.success = true;
  return result;
}

bool RefineAbsolutePose(const std::vector<Eigen::Vector3d>& f,
                        const std::vector<Eigen::Vector3d>& X, const std::vector<char>& mask,
                        double huber_rad, int max_iterations, CameraPoseRC* pose) {
  const int n = static_cast<int>(std::min(f.size(), X.size()));
  std::vector<Eigen::Matrix<double, 3, 2>> bases(n);
  for (int i = 0; i < n; ++i) bases[i] = TangentBasis(f[i]);

  auto evaluate = [&](const CameraPoseRC& p, Eigen::Matrix<double, 6, 6>* h,
                      Eigen::Matrix<double, 6, 1>* g) {
    const Eigen::Matrix3d rt = p.R_world_from_cam.transpose();
    double cost = 0.0;
    if (h) h->setZero();
    if (g) g->setZero();
    for (int i = 0; i < n; ++i) {
      if (!mask.empty() && !mask[i]) continue;
      const Eigen::Vector3d pc = rt * (X[i] - p.C);
      const double norm = pc.norm();
      if (!(norm > 0.0)) continue;
      const Eigen::Vector3d dir = pc / norm;
      if (dir.dot(f[i]) < 0.5) {  // beyond 60 degrees: no gradient information, full penalty
        cost += huber_rad * (2.0 * M_PI / 3.0);
        continue;
      }
      const Eigen::Vector2d r = bases[i].transpose() * dir;
      const double rn = r.norm();
      const double w = rn <= huber_rad ? 1.0 : huber_rad / rn;
      cost += rn <= huber_rad ? 0.5 * rn * rn : huber_rad * (rn - 0.5 * huber_rad);
      if (!h) continue;
      Eigen::Matrix<double, 3, 6> dp;
      Eigen::Matrix3d skew;
      skew << 0, -pc.z(), pc.y(), pc.z(), 0, -pc.x(), -pc.y(), pc.x(), 0;
      dp.leftCols<3>() = skew;  // d pc / d theta (R <- R Exp(theta))
      dp.rightCols<3>() = -rt;  // d pc / d C
      const Eigen::Matrix3d dn = (Eigen::Matrix3d::Identity() - dir * dir.transpose()) / norm;
      const Eigen::Matrix<double, 2, 6> j = bases[i].transpose() * dn * dp;
      *h += w * j.transpose() * j;
      *g += w * j.transpose() * r;
    }
    return cost;
  };

  CameraPoseRC current = *pose;
  Eigen::Matrix<double, 6, 6> h;
  Eigen::Matrix<double, 6, 1> g;
  double cost = evaluate(current, &h, &g);
  double lambda = 1e-4;
  for (int it = 0; it < max_iterations; ++it) {
    Eigen::Matrix<double, 6, 6> damped = h;
    damped.diagonal() += lambda * (h.diagonal().array() + 1e-9).matrix();
    Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(damped);
    if (ldlt.info() != Eigen::Success) return false;
    const Eigen::Matrix<double, 6, 1> step = -ldlt.solve(g);
    if (!step.allFinite()) return false;
    CameraPoseRC candidate;
    candidate.R_world_from_cam = current.R_world_from_cam * ExpSO3(step.head<3>());
    candidate.C = current.C + step.tail<3>();
    Eigen::Matrix<double, 6, 6> h_new;
    Eigen::Matrix<double, 6, 1> g_new;
    const double new_cost = evaluate(candidate, &h_new, &g_new);
    if (new_cost <= cost) {
      current = candidate;
      const double improvement = cost - new_cost;
      cost = new_cost;
      h = h_new;
      g = g_new;
      lambda = std::max(1e-8, lambda * 0.1);
      if (improvement < 1e-10 * (1.0 + cost) || step.norm() < 1e-10) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e4) break;
    }
  }
  // Re-orthonormalise.
  Eigen::Quaterniond q(current.R_world_from_cam);
  current.R_world_from_cam = q.normalized().toRotationMatrix();
  *pose = current;
  return true;
}

}  // namespace rigcal::vo
