// SPDX-License-Identifier: Apache-2.0
#include "models/motion_statistics.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <unsupported/Eigen/KroneckerProduct>

#include "models/kronecker.h"
#include "models/linear_solvers.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {

void MotionStatistics::Add(const MotionData& m, int segment, double w) {
  const Eigen::Matrix4d a = RotationConstraintMatrix(m);
  M_.noalias() += w * a.transpose() * a;  // (4.10)
  planar_.Add(m, w);
  const Eigen::Matrix3d i_r0 = Eigen::Matrix3d::Identity() - m.R0;
  H_cc_.noalias() += w * i_r0.transpose() * i_r0;
  g_c_.noalias() += w * i_r0.transpose() * m.C0;
  c0_sq_ += w * m.C0.squaredNorm();
  SegmentSums& s = segments_[segment];
  s.P.noalias() += w * i_r0.transpose() * KronTransposeIdentity(m.Ci);
  s.n += w * m.Ci.squaredNorm();
  s.Q.noalias() += w * m.C0 * m.Ci.transpose();
  s.N.noalias() += w * m.Ci * m.Ci.transpose();
  const double ni = m.Ci.norm(), n0 = m.C0.norm();
  s.len_cross += w * ni * n0;
  s.len_sq += w * ni * ni;
  s.weight += w;
  if (ni > 0.0 && n0 > 0.0) {
    const Eigen::Vector3d ci = m.Ci / ni;
    S_dir_.noalias() += w * ci * (m.C0 / n0).transpose();
    D_dir_.noalias() += w * ci * ci.transpose();
  }
  weight_ += w;
  position_weight_ += w;
  max_rotation_ = std::max(max_rotation_, m.angle0);
  ++motions_;
}

void MotionStatistics::Decay(double f) {
  M_ *= f;
  planar_.Decay(f);
  H_cc_ *= f;
  g_c_ *= f;
  c0_sq_ *= f;
  S_dir_ *= f;
  D_dir_ *= f;
  H_marg_ *= f;
  g_marg_ *= f;
  c0_sq_marg_ *= f;
  weight_ *= f;
  position_weight_ *= f;
  for (auto& [id, s] : segments_) {
    s.P *= f;
    s.n *= f;
    s.Q *= f;
    s.N *= f;
    s.len_cross *= f;
    s.len_sq *= f;
    s.weight *= f;
  }
}

Eigen::Quaterniond MotionStatistics::SolveRotation(Eigen::Vector4d* eigenvalues) const {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(M_);
  if (eigenvalues) *eigenvalues = eig.eigenvalues();
  return Canonical(FromWxyz(eig.eigenvectors().col(0)).normalized());  // (4.11)
}

Eigen::Quaterniond MotionStatistics::SolveTranslationalRotation() const {
  return SolveAbsoluteOrientation(S_dir_);  // (4.30)
}

double MotionStatistics::TranslationalRotationStd(const Eigen::Quaterniond& dq) const {
  return internal::TranslationalRotationStd(S_dir_, D_dir_, dq);
}

PositionSolution MotionStatistics::SolvePosition(const Eigen::Quaterniond& dq,
                                                 const PositionConstraint* constraint) const {
  PositionSolution out;
  // C = fixed + T y with y the free position unknowns: T = I (general) or the plane basis.
  const int m = constraint ? 2 : 3;
  Eigen::MatrixXd t = Eigen::MatrixXd::Identity(3, m);
  Eigen::Vector3d fixed = Eigen::Vector3d::Zero();
  if (constraint) {
    t = constraint->basis;
    fixed = constraint->fixed;
  }
  const int n_open = static_cast<int>(segments_.size());
  const int dim = m + n_open;
  out.unknowns = dim;
  const Eigen::Matrix3d dr = dq.toRotationMatrix();
  const Eigen::Matrix<double, 9, 1> r = Vec(dr);
  const Eigen::Matrix3d h_full = H_cc_ + H_marg_;
  const Eigen::Vector3d g_full = g_c_ + g_marg_;
  // Residual (I - R0)(fixed + T y) + dλ dR C_i - C_0 = (I - R0) T y + dλ dR C_i - C_0', with
  // C_0' = C_0 - (I - R0) fixed.
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(dim);
  h.topLeftCorner(m, m) = t.transpose() * h_full * t;
  b.head(m) = t.transpose() * (g_full - h_full * fixed);
  const double constant =
      c0_sq_ + c0_sq_marg_ - 2.0 * fixed.dot(g_full) + fixed.dot(h_full * fixed);
  int j = m;
  std::vector<int> ids;
  for (const auto& [id, s] : segments_) {
    const Eigen::Vector3d cross = s.P * r;  // sum w (I-R0)^T dR C_i
    h.block(0, j, m, 1) = t.transpose() * cross;
    h.block(j, 0, 1, m) = (t.transpose() * cross).transpose();
    h(j, j) = s.n;
    b(j) = (dr.array() * s.Q.array()).sum() - fixed.dot(cross);  // sum w C_0'^T dR C_i
    ids.push_back(id);
    ++j;
  }
  if (weight_ <= 0.0) return out;
  const Eigen::VectorXd d = h.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd hn = d.asDiagonal() * h * d.asDiagonal();
  out.min_eigenvalue =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(hn, Eigen::EigenvaluesOnly).eigenvalues()(0);
  const bool regular = out.min_eigenvalue > 1e-12;
  Eigen::VectorXd x;
  if (regular) {
    x = d.asDiagonal() * hn.ldlt().solve(d.asDiagonal() * b);
  } else {
    // Least-squares minimum on the determined directions (pseudo-inverse): the residual is
    // still meaningful, the solution is not.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(hn);
    const double cut = 1e-12 * std::max(eig.eigenvalues().maxCoeff(), 1e-300);
    Eigen::VectorXd inv = eig.eigenvalues();
    for (Eigen::Index k = 0; k < inv.size(); ++k) inv(k) = inv(k) > cut ? 1.0 / inv(k) : 0.0;
    x = d.asDiagonal() * (eig.eigenvectors() * inv.asDiagonal() * eig.eigenvectors().transpose() *
                          (d.asDiagonal() * b));
  }
  if (!x.allFinite()) return out;
  out.residual_ss = std::max(0.0, constant - 2.0 * x.dot(b) + x.dot(h * x));
  if (!regular) return out;
  out.C = fixed + t * x.head(m);
  for (int k = 0; k < n_open; ++k) out.scales[ids[k]] = x(m + k);
  // Information of the free position unknowns with the open scales marginalised (Schur).
  Eigen::MatrixXd info = h.topLeftCorner(m, m);
  for (int k = 0; k < n_open; ++k) {
    const Eigen::VectorXd cross = h.block(0, m + k, m, 1);
    if (h(m + k, m + k) > 0.0) info -= cross * cross.transpose() / h(m + k, m + k);
  }
  out.information = t * info * t.transpose();
  out.covariance = t * info.inverse() * t.transpose();
  out.ok = out.covariance.allFinite();
  return out;
}

PlanarFrame MotionStatistics::SolvePlanarFrame() const {
  return internal::SolvePlanarFrame(planar_);
}

PlanarSystemSolution MotionStatistics::SolvePlanarSystem(const PlanarFrame& frame) const {
  std::vector<PlanarSegmentView> views;
  for (const auto& [id, s] : segments_) views.push_back({id, &s.P, &s.Q, &s.N});
  return internal::SolvePlanarSystem(planar_, H_cc_, g_c_, views, frame);
}

RefinementPrior MotionStatistics::Quadratic() const {
  RefinementPrior prior;
  prior.weight = weight_;
  prior.position_weight = position_weight_;
  prior.motions = motions_;
  prior.rotation = M_;
  const int n = static_cast<int>(segments_.size());
  const int dim = 4 + 9 * n;
  Eigen::MatrixXd g = Eigen::MatrixXd::Zero(dim, dim);
  // Each motion's residual is A_k u with A_k = [(I - R0), (C_i^T ⊗ I3) in its segment's block,
  // -C0]; the Gram matrix sum w A_k^T A_k from the sums:
  g.topLeftCorner<3, 3>() = H_cc_ + H_marg_;
  g.block<3, 1>(0, dim - 1) = -(g_c_ + g_marg_);
  g(dim - 1, dim - 1) = c0_sq_ + c0_sq_marg_;
  int j = 3;
  for (const auto& [id, seg] : segments_) {
    prior.segments.push_back(id);
    g.block<3, 9>(0, j) = seg.P;  // (I-R0)^T (C_i^T ⊗ I3)
    g.block<9, 9>(j, j) = Eigen::kroneckerProduct(seg.N, Eigen::Matrix3d::Identity());
    g.block<9, 1>(j, dim - 1) = -Eigen::Map<const Eigen::Matrix<double, 9, 1>>(seg.Q.data());
    j += 9;
  }
  prior.position = g.selfadjointView<Eigen::Upper>();
  return prior;
}

std::map<int, double> MotionStatistics::SolveTranslationalScales() const {
  std::map<int, double> scales;
  for (const auto& [id, s] : segments_) {
    if (s.len_sq > 0.0) scales[id] = s.len_cross / s.len_sq;  // (4.32)
  }
  return scales;
}

void MotionStatistics::MarginaliseSegment(int segment, const Eigen::Quaterniond& dq,
                                          const PlanarFrame& frame) {
  auto it = segments_.find(segment);
  if (it == segments_.end()) return;
  const SegmentSums& s = it->second;
  MarginalisePlanarSegment({segment, &s.P, &s.Q, &s.N}, frame, &planar_);
  if (s.n > 0.0) {
    const Eigen::Matrix3d dr = dq.toRotationMatrix();
    const Eigen::Vector3d h = s.P * Vec(dr);
    const double rhs = (dr.array() * s.Q.array()).sum();
    H_marg_ -= h * h.transpose() / s.n;
    g_marg_ -= h * rhs / s.n;
    c0_sq_marg_ -= rhs * rhs / s.n;
  }
  closed_scales_[segment] = s.last_scale;
  segments_.erase(it);
}

void MotionStatistics::ResetPosition() {
  H_cc_.setZero();
  g_c_.setZero();
  c0_sq_ = 0.0;
  H_marg_.setZero();
  g_marg_.setZero();
  c0_sq_marg_ = 0.0;
  position_weight_ = 0.0;
  S_dir_.setZero();
  D_dir_.setZero();
  planar_.ResetPosition();
  segments_.clear();
}

void MotionStatistics::SetSegmentScale(int segment, double scale) {
  auto it = segments_.find(segment);
  if (it != segments_.end()) it->second.last_scale = scale;
}

MotionSums MotionStatistics::Sums() const {
  MotionSums s;
  s.rotation = M_;
  s.planar = planar_;
  s.h_cc = H_cc_;
  s.g_c = g_c_;
  s.c0_sq = c0_sq_;
  s.s_dir = S_dir_;
  s.d_dir = D_dir_;
  s.h_marg = H_marg_;
  s.g_marg = g_marg_;
  s.c0_sq_marg = c0_sq_marg_;
  s.weight = weight_;
  s.position_weight = position_weight_;
  s.max_rotation = max_rotation_;
  s.motions = motions_;
  s.segments = segments_;
  s.closed_scales = closed_scales_;
  return s;
}

MotionStatistics MotionStatistics::FromSums(const MotionSums& s) {
  MotionStatistics m;
  m.M_ = s.rotation;
  static_cast<PlanarMotionSums&>(m.planar_) = s.planar;
  m.H_cc_ = s.h_cc;
  m.g_c_ = s.g_c;
  m.c0_sq_ = s.c0_sq;
  m.S_dir_ = s.s_dir;
  m.D_dir_ = s.d_dir;
  m.H_marg_ = s.h_marg;
  m.g_marg_ = s.g_marg;
  m.c0_sq_marg_ = s.c0_sq_marg;
  m.weight_ = s.weight;
  m.position_weight_ = s.position_weight.value_or(s.weight);
  m.max_rotation_ = s.max_rotation;
  m.motions_ = s.motions;
  m.segments_ = s.segments;
  m.closed_scales_ = s.closed_scales;
  return m;
}

}  // namespace rigcal::internal
