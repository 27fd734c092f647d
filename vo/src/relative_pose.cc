// SPDX-License-Identifier: Apache-2.0
#include "relative_pose.h"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "ransac_sampling.h"

namespace rigcal::vo {
namespace {

// Polynomials of degree <= 3 in (x, y, z), 20 coefficients. The 10 cubic monomials come first
// (they are eliminated), then the basis of the quotient ring: x^2 xy xz y^2 yz z^2 x y z 1.
constexpr int kNumMonomials = 20;
using Poly = std::array<double, kNumMonomials>;

constexpr int kExponents[kNumMonomials][3] = {
    {3, 0, 0}, {2, 1, 0}, {2, 0, 1}, {1, 2, 0}, {1, 1, 1}, {1, 0, 2}, {0, 3, 0},
    {0, 2, 1}, {0, 1, 2}, {0, 0, 3}, {2, 0, 0}, {1, 1, 0}, {1, 0, 1}, {0, 2, 0},
    {0, 1, 1}, {0, 0, 2}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0, 0, 0}};

struct ProductTable {
  int index[kNumMonomials][kNumMonomials];
  ProductTable() {
    for (int i = 0; i < kNumMonomials; ++i) {
      for (int j = 0; j < kNumMonomials; ++j) {
        index[i][j] = -1;
        const int e[3] = {kExponents[i][0] + kExponents[j][0], kExponents[i][1] + kExponents[j][1],
                          kExponents[i][2] + kExponents[j][2]};
        for (int k = 0; k < kNumMonomials; ++k) {
          if (kExponents[k][0] == e[0] && kExponents[k][1] == e[1] && kExponents[k][2] == e[2]) {
            index[i][j] = k;
          }
        }
      }
    }
  }
};

const ProductTable& Products() {
  static const ProductTable table;
  return table;
}

// Product of two polynomials whose degrees add up to at most 3.
Poly Multiply(const Poly& a, const Poly& b) {
  const ProductTable& table = Products();
  Poly out{};
  for (int i = 0; i < kNumMonomials; ++i) {
    if (a[i] == 0.0) continue;
    for (int j = 0; j < kNumMonomials; ++j) {
      if (b[j] == 0.0) continue;
      const int k = table.index[i][j];
      if (k >= 0) out[k] += a[i] * b[j];
    }
  }
  return out;
}

Poly Add(const Poly& a, const Poly& b, double b_factor = 1.0) {
  Poly out;
  for (int i = 0; i < kNumMonomials; ++i) out[i] = a[i] + b_factor * b[i];
  return out;
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

Eigen::Matrix3d ExpRotation(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-15) return Eigen::Matrix3d::Identity() + Skew(w);
  return Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
}

// First-order (Sampson) angular distance of a correspondence to the epipolar constraint of E,
// radians: perturbations of both bearings in their tangent planes.
double SampsonAngle(const Eigen::Matrix3d& E, const Eigen::Vector3d& f1,
                    const Eigen::Vector3d& f2) {
  const Eigen::Vector3d n1 = E * f2;
  const Eigen::Vector3d n2 = E.transpose() * f1;
  const double g = f1.dot(n1);
  const double den = n1.squaredNorm() - g * g + n2.squaredNorm() - f2.dot(n2) * f2.dot(n2);
  return den > 1e-30 ? g / std::sqrt(den) : 0.0;
}

// Levenberg-Marquardt on (R, direction of C) minimising Huber(SampsonAngle) over `mask`.
void RefineRelativePose(const std::vector<Eigen::Vector3d>& f1,
                        const std::vector<Eigen::Vector3d>& f2, const std::vector<char>& mask,
                        double huber, int max_iterations, RelativePose* pose) {
  std::vector<int> used;
  for (size_t i = 0; i < mask.size(); ++i) {
    if (mask[i]) used.push_back(static_cast<int>(i));
  }
  if (used.size() < 6) return;
  const int m = static_cast<int>(used.size());
  auto residuals = [&](const RelativePose& p, Eigen::VectorXd* r) {
    const Eigen::Matrix3d E = EssentialFromPose(p);
    r->resize(m);
    double cost = 0.0;
    for (int k = 0; k < m; ++k) {
      const double e = SampsonAngle(E, f1[used[k]], f2[used[k]]);
      const double a = std::abs(e);
      const double w = a <= huber ? 1.0 : std::sqrt(huber / a);  // IRLS weight on residual
      (*r)(k) = w * e;
      cost += a <= huber ? 0.5 * e * e : huber * (a - 0.5 * huber);
    }
    return cost;
  };
  auto apply = [](const RelativePose& p, const Eigen::Matrix<double, 5, 1>& d) {
    RelativePose out;
    out.R_1_from_2 = p.R_1_from_2 * ExpRotation(d.head<3>());
    const Eigen::Vector3d t = p.C2_in_1.normalized();
    const Eigen::Vector3d a =
        std::abs(t.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    const Eigen::Vector3d b1 = (a - a.dot(t) * t).normalized();
    const Eigen::Vector3d b2 = t.cross(b1);
    out.C2_in_1 = (t + d(3) * b1 + d(4) * b2).normalized();
    return out;
  };
  RelativePose current = *pose;
  Eigen::VectorXd r, r_plus, r_minus;
  double cost = residuals(current, &r);
  double lambda = 1e-3;
  Eigen::MatrixXd jacobian(m, 5);
  for (int it = 0; it < max_iterations; ++it) {
    for (int j = 0; j < 5; ++j) {
      Eigen::Matrix<double, 5, 1> d = Eigen::Matrix<double, 5, 1>::Zero();
      d(j) = 1e-6;
      residuals(apply(current, d), &r_plus);
      residuals(apply(current, -d), &r_minus);
      jacobian.col(j) = (r_plus - r_minus) / 2e-6;
    }
    const Eigen::Matrix<double, 5, 5> h = jacobian.transpose() * jacobian;
    const Eigen::Matrix<double, 5, 1> g = jacobian.transpose() * r;
    bool improved = false;
    while (lambda < 1e6) {
      Eigen::Matrix<double, 5, 5> damped = h;
      damped.diagonal() += lambda * (h.diagonal().array() + 1e-12).matrix();
      const Eigen::Matrix<double, 5, 1> step = -damped.ldlt().solve(g);
      if (!step.allFinite()) return;
      const RelativePose candidate = apply(current, step);
      Eigen::VectorXd r_new;
      const double new_cost = residuals(candidate, &r_new);
      if (new_cost < cost) {
        const double gain = cost - new_cost;
        current = candidate;
        r = r_new;
        cost = new_cost;
        lambda = std::max(1e-9, lambda * 0.1);
        improved = gain > 1e-12 * (1.0 + cost);
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }
  *pose = current;
}

}  // namespace

Eigen::Matrix3d EssentialFromPose(const RelativePose& pose) {
  return Skew(pose.C2_in_1) * pose.R_1_from_2;
}

std::vector<Eigen::Matrix3d> SolveEssentialFivePoint(const std::array<Eigen::Vector3d, 5>& f1,
                                                     const std::array<Eigen::Vector3d, 5>& f2) {
  // Rows of the linear constraint f1^T E f2 = 0 on vec(E) (row-major).
  Eigen::Matrix<double, 9, 9> a = Eigen::Matrix<double, 9, 9>::Zero();
  for (int n = 0; n < 5; ++n) {
    const Eigen::Vector3d p = f1[n].normalized();
    const Eigen::Vector3d q = f2[n].normalized();
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) a(n, 3 * i + j) = p(i) * q(j);
    }
  }
  // Null space of the 5x9 system: the 4 right singular vectors of the smallest singular values.
  Eigen::JacobiSVD<Eigen::Matrix<double, 9, 9>> svd(a, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 9>& v = svd.matrixV();
  if (svd.singularValues()(4) < 1e-10 * svd.singularValues()(0)) return {};

  // E = x X + y Y + z Z + W, each entry a polynomial of degree 1.
  std::array<std::array<Poly, 3>, 3> e;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Poly p{};
      p[16] = v(3 * i + j, 5);
      p[17] = v(3 * i + j, 6);
      p[18] = v(3 * i + j, 7);
      p[19] = v(3 * i + j, 8);
      e[i][j] = p;
    }
  }
  // E E^T (degree 2) and its trace.
  std::array<std::array<Poly, 3>, 3> eet;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Poly s{};
      for (int k = 0; k < 3; ++k) s = Add(s, Multiply(e[i][k], e[j][k]));
      eet[i][j] = s;
    }
  }
  const Poly trace = Add(Add(eet[0][0], eet[1][1]), eet[2][2]);

  Eigen::Matrix<double, 10, 20> m;
  // 2 E E^T E - trace(E E^T) E = 0: nine cubic equations.
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Poly s{};
      for (int k = 0; k < 3; ++k) s = Add(s, Multiply(eet[i][k], e[k][j]), 2.0);
      s = Add(s, Multiply(trace, e[i][j]), -1.0);
      for (int c = 0; c < kNumMonomials; ++c) m(3 * i + j, c) = s[c];
    }
  }
  // det(E) = 0.
  const Poly det =
      Add(Add(Multiply(e[0][0], Add(Multiply(e[1][1], e[2][2]), Multiply(e[1][2], e[2][1]), -1.0)),
              Multiply(e[0][1], Add(Multiply(e[1][0], e[2][2]), Multiply(e[1][2], e[2][0]), -1.0)),
              -1.0),
          Multiply(e[0][2], Add(Multiply(e[1][0], e[2][1]), Multiply(e[1][1], e[2][0]), -1.0)));
  for (int c = 0; c < kNumMonomials; ++c) m(9, c) = det[c];

  // Gauss-Jordan: cubic monomials = -B * basis.
  const Eigen::Matrix<double, 10, 10> lead = m.leftCols<10>();
  Eigen::FullPivLU<Eigen::Matrix<double, 10, 10>> lu(lead);
  if (!lu.isInvertible()) return {};
  const Eigen::Matrix<double, 10, 10> b = lu.solve(m.rightCols<10>());

  // Action matrix of multiplication by x on the basis (x^2 xy xz y^2 yz z^2 x y z 1).
  Eigen::Matrix<double, 10, 10> action = Eigen::Matrix<double, 10, 10>::Zero();
  for (int r = 0; r < 6; ++r) action.row(r) = -b.row(r);  // x^3 x^2y x^2z xy^2 xyz xz^2
  action(6, 0) = 1.0;                                     // x * x = x^2
  action(7, 1) = 1.0;                                     // x * y = xy
  action(8, 2) = 1.0;                                     // x * z = xz
  action(9, 6) = 1.0;                                     // x * 1 = x

  Eigen::EigenSolver<Eigen::Matrix<double, 10, 10>> eig(action, true);
  if (eig.info() != Eigen::Success) return {};
  std::vector<Eigen::Matrix3d> solutions;
  for (int s = 0; s < 10; ++s) {
    if (std::abs(eig.eigenvalues()(s).imag()) > 1e-8 * (1.0 + std::abs(eig.eigenvalues()(s))))
      continue;
    const Eigen::Matrix<double, 10, 1> vec = eig.eigenvectors().col(s).real();
    if (std::abs(vec(9)) < 1e-12) continue;
    const double x = vec(6) / vec(9);
    const double y = vec(7) / vec(9);
    const double z = vec(8) / vec(9);
    Eigen::Matrix3d essential;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const int k = 3 * i + j;
        essential(i, j) = x * v(k, 5) + y * v(k, 6) + z * v(k, 7) + v(k, 8);
      }
    }
    const double norm = essential.norm();
    if (!(norm > 0.0) || !std::isfinite(norm)) continue;
    solutions.push_back(essential / norm);
  }
  return solutions;
}

double EpipolarAngle(const Eigen::Matrix3d& E, const Eigen::Vector3d& f1,
                     const Eigen::Vector3d& f2) {
  const Eigen::Vector3d n1 = E * f2;              // normal of the epipolar plane in view 1
  const Eigen::Vector3d n2 = E.transpose() * f1;  // ... in view 2
  const double dot = std::abs(f1.dot(n1));        // = |f2 . n2|
  const double norm = std::min(n1.norm(), n2.norm());
  if (!(norm > 0.0)) return M_PI / 2;
  return std::asin(std::min(1.0, dot / norm));
}

std::array<RelativePose, 4> DecomposeEssential(const Eigen::Matrix3d& E) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  Eigen::Matrix3d v = svd.matrixV();
  if (u.determinant() < 0) u = -u;
  if (v.determinant() < 0) v = -v;
  Eigen::Matrix3d w;
  w << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  const Eigen::Matrix3d r1 = u * w * v.transpose();
  const Eigen::Matrix3d r2 = u * w.transpose() * v.transpose();
  const Eigen::Vector3d t = u.col(2).normalized();
  std::array<RelativePose, 4> out;
  out[0] = {r1, t};
  out[1] = {r1, -t};
  out[2] = {r2, t};
  out[3] = {r2, -t};
  return out;
}

bool RayDepths(const RelativePose& pose, const Eigen::Vector3d& f1, const Eigen::Vector3d& f2,
               double* d1, double* d2) {
  const Eigen::Vector3d g = pose.R_1_from_2 * f2;
  const double a = f1.dot(g);
  const double den = 1.0 - a * a;
  if (den < 1e-12) return false;
  const double f1c = f1.dot(pose.C2_in_1);
  const double gc = g.dot(pose.C2_in_1);
  *d1 = (f1c - a * gc) / den;
  *d2 = (a * f1c - gc) / den;
  return true;
}

Eigen::Matrix3d BestRotation(const std::vector<Eigen::Vector3d>& f1,
                             const std::vector<Eigen::Vector3d>& f2) {
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < f1.size() && i < f2.size(); ++i) h += f2[i] * f1[i].transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixV() * d * svd.matrixU().transpose();
}

int InliersInFront(const RelativePose& pose, const std::vector<Eigen::Vector3d>& f1,
                   const std::vector<Eigen::Vector3d>& f2, const std::vector<char>& inliers) {
  int front = 0;
  for (size_t i = 0; i < f1.size() && i < inliers.size(); ++i) {
    if (!inliers[i]) continue;
    double d1 = 0, d2 = 0;
    if (RayDepths(pose, f1[i], f2[i], &d1, &d2) && d1 > 0 && d2 > 0) ++front;
  }
  return front;
}

RelativePoseRansacResult EstimateRelativePose(const std::vector<Eigen::Vector3d>& f1,
                                              const std::vector<Eigen::Vector3d>& f2,
                                              const RelativePoseRansacOptions& options,
                                              std::mt19937* rng) {
  RelativePoseRansacResult result;
  const int n = static_cast<int>(std::min(f1.size(), f2.size()));
  if (n < 5 || n < options.min_inliers) return result;
  const double sin_threshold = std::sin(options.max_epipolar_angle_rad);

  auto count_inliers = [&](const Eigen::Matrix3d& E, std::vector<char>* mask) {
    int count = 0;
    for (int i = 0; i < n; ++i) {
      const Eigen::Vector3d n1 = E * f2[i];
      const Eigen::Vector3d n2 = E.transpose() * f1[i];
      const double dot = std::abs(f1[i].dot(n1));
      const bool in = dot <= sin_threshold * std::min(n1.norm(), n2.norm());
      if (mask) (*mask)[i] = in;
      count += in;
    }
    return count;
  };

  int best_count = -1;
  Eigen::Matrix3d best_E = Eigen::Matrix3d::Zero();
  int needed = options.max_iterations;
  int iteration = 0;
  std::array<int, 5> sample;
  std::array<Eigen::Vector3d, 5> s1, s2;
  for (; iteration < std::min(needed, options.max_iterations); ++iteration) {
    SampleDistinct(n, &sample, rng);
    for (int k = 0; k < 5; ++k) {
      s1[k] = f1[sample[k]];
      s2[k] = f2[sample[k]];
    }
    for (const Eigen::Matrix3d& E : SolveEssentialFivePoint(s1, s2)) {
      const int count = count_inliers(E, nullptr);
      if (count > best_count) {
        best_count = count;
        best_E = E;
        needed = RansacIterations(static_cast<double>(count) / n, 5, options.confidence);
      }
    }
  }
  result.iterations = iteration;
  result.E = best_E;
  if (best_count < options.min_inliers) {
    result.num_inliers = std::max(best_count, 0);
    return result;
  }

  result.inliers.assign(n, 0);
  result.num_inliers = count_inliers(best_E, &result.inliers);

  // The decomposition with most inliers in front of both views.
  int best_front = -1;
  for (const RelativePose& candidate : DecomposeEssential(best_E)) {
    const int front = InliersInFront(candidate, f1, f2, result.inliers);
    if (front > best_front) {
      best_front = front;
      result.pose = candidate;
    }
  }
  // Maximum-likelihood style refinement on the inliers, then the final inlier set.
  RefineRelativePose(f1, f2, result.inliers, options.max_epipolar_angle_rad, 10, &result.pose);
  result.E = EssentialFromPose(result.pose);
  result.num_inliers = count_inliers(result.E, &result.inliers);
  result.num_in_front = InliersInFront(result.pose, f1, f2, result.inliers);
  result.success = true;
  return result;
}

}  // namespace rigcal::vo
