// SPDX-License-Identifier: Apache-2.0
#include "models/linear_solvers.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdint>
#include <limits>

#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

Eigen::Matrix4d RotationSystem(const std::vector<MotionData>& motions) {
  Eigen::Matrix4d sum = Eigen::Matrix4d::Zero();
  for (const auto& m : motions) {
    const Eigen::Matrix4d a = RotationConstraintMatrix(m);
    sum.noalias() += a.transpose() * a;
  }
  return sum;
}

LinearRotation SmallestEigenvector(const Eigen::Matrix4d& system) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(system);
  LinearRotation out;
  out.eigenvalues = eig.eigenvalues();
  out.q = FromWxyz(eig.eigenvectors().col(0)).normalized();  // (4.11)
  return out;
}

}  // namespace

Eigen::Matrix4d RotationConstraintMatrix(const MotionData& m) {
  return LeftMultiplicationMatrix(m.q0) - RightMultiplicationMatrix(m.qi);  // (4.7)
}

LinearRotation SolveLinearRotation(std::vector<MotionData>* motions) {
  // Near 180 degrees the scalar parts are below the noise and canonical signs may disagree
  // between master and slave; one such motion spoils the first estimate. Resolve those signs
  // first: by trying every combination when there are few, else from the other motions.
  constexpr double kAmbiguousW = 0.2588;  // cos(75 deg): rotations beyond 150 degrees
  std::vector<size_t> ambiguous;
  for (size_t k = 0; k < motions->size(); ++k) {
    const auto& m = (*motions)[k];
    if (std::min(std::abs(m.q0[0]), std::abs(m.qi[0])) < kAmbiguousW) ambiguous.push_back(k);
  }
  if (!ambiguous.empty() && ambiguous.size() <= 10) {
    const Eigen::Matrix4d base = [&] {
      Eigen::Matrix4d sum = Eigen::Matrix4d::Zero();
      size_t next = 0;
      for (size_t k = 0; k < motions->size(); ++k) {
        if (next < ambiguous.size() && ambiguous[next] == k) {
          ++next;
          continue;
        }
        const Eigen::Matrix4d a = RotationConstraintMatrix((*motions)[k]);
        sum.noalias() += a.transpose() * a;
      }
      return sum;
    }();
    double best = std::numeric_limits<double>::infinity();
    uint32_t best_mask = 0;
    for (uint32_t mask = 0; mask < (1u << ambiguous.size()); ++mask) {
      Eigen::Matrix4d sum = base;
      for (size_t j = 0; j < ambiguous.size(); ++j) {
        MotionData m = (*motions)[ambiguous[j]];
        if (mask & (1u << j)) m.qi = -m.qi;
        const Eigen::Matrix4d a = RotationConstraintMatrix(m);
        sum.noalias() += a.transpose() * a;
      }
      const double smallest =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(sum, Eigen::EigenvaluesOnly)
              .eigenvalues()(0);
      if (smallest < best) {
        best = smallest;
        best_mask = mask;
      }
    }
    for (size_t j = 0; j < ambiguous.size(); ++j) {
      if (best_mask & (1u << j)) (*motions)[ambiguous[j]].qi = -(*motions)[ambiguous[j]].qi;
    }
  } else if (!ambiguous.empty() && motions->size() - ambiguous.size() >= 2) {
    std::vector<MotionData> clear;
    size_t next = 0;
    for (size_t k = 0; k < motions->size(); ++k) {
      if (next < ambiguous.size() && ambiguous[next] == k) {
        ++next;
      } else {
        clear.push_back((*motions)[k]);
      }
    }
    AlignSignsWith(ToWxyz(SmallestEigenvector(RotationSystem(clear)).q), motions);
  }
  LinearRotation first = SmallestEigenvector(RotationSystem(*motions));
  AlignSignsWith(ToWxyz(first.q), motions);
  LinearRotation second = SmallestEigenvector(RotationSystem(*motions));
  second.q = Canonical(second.q);
  return second;
}

Eigen::Quaterniond SolveAbsoluteOrientation(const std::vector<Eigen::Vector3d>& source,
                                            const std::vector<Eigen::Vector3d>& target) {
  // Horn (A.21): S_ab = sum a_k b'_k with a from source, b from target.
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < source.size(); ++k) s += source[k] * target[k].transpose();
  return SolveAbsoluteOrientation(s);
}

Eigen::Quaterniond SolveAbsoluteOrientation(const Eigen::Matrix3d& s) {
  const double sxx = s(0, 0), sxy = s(0, 1), sxz = s(0, 2);
  const double syx = s(1, 0), syy = s(1, 1), syz = s(1, 2);
  const double szx = s(2, 0), szy = s(2, 1), szz = s(2, 2);
  Eigen::Matrix4d n;
  n << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(n);
  return Canonical(FromWxyz(eig.eigenvectors().col(3)).normalized());
}

Eigen::Quaterniond SolveTranslationalRotation(const std::vector<MotionData>& motions) {
  std::vector<Eigen::Vector3d> source, target;
  for (const auto& m : motions) {
    const double ni = m.Ci.norm(), n0 = m.C0.norm();
    if (ni <= 0.0 || n0 <= 0.0) continue;
    source.push_back(m.Ci / ni);  // c_i^k (4.29)
    target.push_back(m.C0 / n0);  // c_0^k
  }
  return SolveAbsoluteOrientation(source, target);
}

double TranslationalRotationStd(const Eigen::Matrix3d& s, const Eigen::Matrix3d& d,
                                const Eigen::Quaterniond& dq) {
  const Eigen::Matrix3d dr = dq.toRotationMatrix();
  const double w = d.trace();  // sum of the weights (unit directions)
  if (w <= 0.0) return std::numeric_limits<double>::infinity();
  // sum w |c_0 - dR c_i|^2 = 2 w - 2 tr(dR S).
  const double residual_ss = std::max(0.0, 2.0 * w - 2.0 * (dr * s).trace());
  const double variance = residual_ss / std::max(1.0, 2.0 * w - 3.0);
  // d(Exp(δ) dR c_i)/dδ = -[dR c_i]x: information sum w (I - v v^T) with v = dR c_i.
  const Eigen::Matrix3d information = w * Eigen::Matrix3d::Identity() - dr * d * dr.transpose();
  // The noisy directions add information of their own about the rotation about a line all
  // translations share: 2 σ_i² per motion, σ_i² the slave's per-component direction noise,
  // about variance / 2 (the residual has the master's and the slave's). What is left is the
  // spread of the true directions; below twice the noise's share the rotation is undetermined.
  const double smallest =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(information).eigenvalues()(0);
  const double signal = smallest - w * variance;
  if (!(signal > 2.0 * w * variance) || !(signal > 1e-12 * w)) {
    return std::numeric_limits<double>::infinity();
  }
  return std::sqrt(variance / signal);
}

double TranslationalRotationStd(const std::vector<MotionData>& motions,
                                const Eigen::Quaterniond& dq) {
  Eigen::Matrix3d s = Eigen::Matrix3d::Zero(), d = Eigen::Matrix3d::Zero();
  for (const auto& m : motions) {
    const double ni = m.Ci.norm(), n0 = m.C0.norm();
    if (ni <= 0.0 || n0 <= 0.0) continue;
    s += (m.Ci / ni) * (m.C0 / n0).transpose();
    d += (m.Ci / ni) * (m.Ci / ni).transpose();
  }
  return TranslationalRotationStd(s, d, dq);
}

std::vector<double> SolveTranslationalScales(const std::vector<MotionData>& motions,
                                             int num_scales) {
  std::vector<double> ab(num_scales, 0.0), aa(num_scales, 0.0);
  for (const auto& m : motions) {
    const double a = m.Ci.norm(), b = m.C0.norm();  // (4.32): a_k = |C_i|, b_k = |C_0|
    ab[m.scale_index] += a * b;
    aa[m.scale_index] += a * a;
  }
  std::vector<double> scales(num_scales, 0.0);
  for (int s = 0; s < num_scales; ++s) scales[s] = aa[s] > 0.0 ? ab[s] / aa[s] : 0.0;
  return scales;
}

double RotationResidual(const MotionData& m, const Eigen::Vector4d& dq) {
  return (RotationConstraintMatrix(m) * dq).norm();
}

double PositionResidual(const MotionData& m, const Eigen::Quaterniond& dq,
                        const Eigen::Vector3d& dC, double scale) {
  return ((Eigen::Matrix3d::Identity() - m.R0) * dC + scale * (dq * m.Ci) - m.C0).norm();
}

double TranslationalResidual(const MotionData& m, const Eigen::Quaterniond& dq, double scale) {
  return (scale * (dq * m.Ci) - m.C0).norm();
}

}  // namespace rigcal::internal
