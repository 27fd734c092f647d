// SPDX-License-Identifier: Apache-2.0
#include "models/planar_solver.h"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <complex>
#include <limits>

#include "models/kronecker.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return s;
}

// Spread (RMS angle about the principal axis) of a scatter matrix of rotation vectors, from
// its ascending eigenvalues.
double Spread(const Eigen::Vector3d& ascending) {
  const Eigen::Vector3d e = ascending.cwiseMax(0.0);
  return e(2) > 0.0 ? std::atan(std::sqrt((e(0) + e(1)) / e(2))) * kDegPerRad : 0.0;
}

// The (u, w) columns of one segment in the planar system (see the header): cross terms with
// dC (3-D, before projection onto the plane), the diagonal and the right-hand sides.
struct SegmentTerms {
  Eigen::Vector3d hu, hw;
  double nn = 0.0;
  double bu = 0.0, bw = 0.0;
};

SegmentTerms TermsOf(const PlanarSegmentView& s, const PlanarFrame& frame) {
  const Eigen::Matrix3d ra = frame.align.toRotationMatrix();
  const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - frame.axis * frame.axis.transpose();
  const Eigen::Matrix3d xu = p * ra;                 // u P R_a C_i
  const Eigen::Matrix3d xw = Skew(frame.axis) * ra;  // w [a]x R_a C_i
  SegmentTerms t;
  t.hu = *s.P * Vec(xu);  // sum w (I - R_0)^T P R_a C_i
  t.hw = *s.P * Vec(xw);
  // sum w |P R_a C_i|^2 = sum w |[a]x R_a C_i|^2; the (u, w) cross term is a skew form: 0.
  t.nn = ((ra.transpose() * p * ra).array() * s.N->array()).sum();
  t.bu = (xu.array() * s.Q->array()).sum();  // sum w C_0^T P R_a C_i
  t.bw = (xw.array() * s.Q->array()).sum();
  return t;
}

}  // namespace

void PlanarSums::Add(const MotionData& m, double w) {
  const Eigen::Vector3d v0 = m.q0.tail<3>(), vi = m.qi.tail<3>();
  v00.noalias() += w * v0 * v0.transpose();
  vii.noalias() += w * vi * vi.transpose();
  v0i.noalias() += w * v0 * vi.transpose();
  const Eigen::Matrix3d i_r0 = Eigen::Matrix3d::Identity() - m.R0;
  k.noalias() += w * i_r0.transpose() * KronTransposeIdentity(m.C0);
  c0c0.noalias() += w * m.C0 * m.C0.transpose();
}

void PlanarSums::Decay(double f) {
  v00 *= f;
  vii *= f;
  v0i *= f;
  k *= f;
  c0c0 *= f;
  h_marg *= f;
  g_marg *= f;
  c_marg *= f;
}

void PlanarSums::ResetPosition() {
  k.setZero();
  c0c0.setZero();
  h_marg.setZero();
  g_marg.setZero();
  c_marg = 0.0;
}

Eigen::Matrix<double, 3, 2> PlaneBasis(const Eigen::Vector3d& axis) {
  Eigen::Index least = 0;
  axis.cwiseAbs().minCoeff(&least);
  const Eigen::Vector3d b1 = axis.cross(Eigen::Vector3d::Unit(least)).normalized();
  Eigen::Matrix<double, 3, 2> basis;
  basis.col(0) = b1;
  basis.col(1) = axis.cross(b1);
  return basis;
}

PlanarFrame SolvePlanarFrame(const PlanarSums& sums) {
  PlanarFrame f;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> master(sums.v00);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> slave(sums.vii);
  f.master_spread_deg = Spread(master.eigenvalues());
  f.slave_spread_deg = Spread(slave.eigenvalues());
  if (!(master.eigenvalues()(2) > 0.0) || !(slave.eigenvalues()(2) > 0.0)) return f;
  f.axis = master.eigenvectors().col(2).normalized();
  // A definite sign (the eigenvector's is arbitrary): the largest component positive.
  Eigen::Index largest = 0;
  f.axis.cwiseAbs().maxCoeff(&largest);
  if (f.axis(largest) < 0.0) f.axis = -f.axis;
  f.slave_axis = slave.eigenvectors().col(2).normalized();
  // Sign: the signed rotation vectors of master and slave agree along the axes.
  if (f.axis.dot(sums.v0i * f.slave_axis) < 0.0) f.slave_axis = -f.slave_axis;
  f.align = Eigen::Quaterniond::FromTwoVectors(f.slave_axis, f.axis).normalized();
  f.basis = PlaneBasis(f.axis);
  f.ok = f.axis.allFinite() && f.align.coeffs().allFinite();
  return f;
}

PlanarSystemSolution SolvePlanarSystem(const PlanarSums& sums, const Eigen::Matrix3d& h_cc,
                                       const Eigen::Vector3d& g_c,
                                       const std::vector<PlanarSegmentView>& segments,
                                       const PlanarFrame& frame) {
  PlanarSystemSolution out;
  if (!frame.ok || segments.empty()) return out;
  const int n = static_cast<int>(segments.size());
  const int dim = 2 + 2 * n;
  out.unknowns = dim;
  const Eigen::Vector3d& a = frame.axis;
  const Eigen::Matrix<double, 3, 2>& b = frame.basis;
  const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - a * a.transpose();
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(dim, dim);
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(dim);
  h.topLeftCorner<2, 2>() = b.transpose() * (h_cc + sums.h_marg) * b;
  // sum w (I - R_0)^T P C_0 = g_c - sum w (I - R_0)^T a a^T C_0.
  const Eigen::Matrix3d aat = a * a.transpose();
  rhs.head<2>() = b.transpose() * (g_c - sums.k * Vec(aat) + sums.g_marg);
  double constant = (p.array() * sums.c0c0.array()).sum() + sums.c_marg;  // sum w |P C_0|^2
  for (int j = 0; j < n; ++j) {
    const SegmentTerms t = TermsOf(segments[j], frame);
    const int iu = 2 + 2 * j, iw = iu + 1;
    h.block<2, 1>(0, iu) = b.transpose() * t.hu;
    h.block<2, 1>(0, iw) = b.transpose() * t.hw;
    h.block<1, 2>(iu, 0) = h.block<2, 1>(0, iu).transpose();
    h.block<1, 2>(iw, 0) = h.block<2, 1>(0, iw).transpose();
    h(iu, iu) = t.nn;
    h(iw, iw) = t.nn;
    rhs(iu) = t.bu;
    rhs(iw) = t.bw;
  }
  const Eigen::VectorXd d = h.diagonal().cwiseMax(1e-300).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd hn = d.asDiagonal() * h * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(hn, Eigen::EigenvaluesOnly);
  out.min_eigenvalue = eig.eigenvalues()(0);
  if (!(out.min_eigenvalue > 1e-12)) return out;
  const Eigen::VectorXd x = d.asDiagonal() * hn.ldlt().solve(d.asDiagonal() * rhs);
  if (!x.allFinite()) return out;
  out.p = x.head<2>();
  out.residual_ss = std::max(0.0, constant - 2.0 * x.dot(rhs) + x.dot(h * x));
  // γ per segment from (u, w) = dλ (cos γ, sin γ); combined as the information-weighted
  // circular mean, var(γ_j) = J H^-1 J^T with J = (-w, u) / dλ^2.
  const Eigen::MatrixXd h_inv = d.asDiagonal() * hn.inverse() * d.asDiagonal();
  std::complex<double> mean(0.0, 0.0);
  for (int j = 0; j < n; ++j) {
    const int iu = 2 + 2 * j, iw = iu + 1;
    const double u = x(iu), w = x(iw);
    const double l2 = u * u + w * w;
    if (!(l2 > 0.0)) continue;
    const Eigen::Vector2d jac(-w / l2, u / l2);
    Eigen::Matrix2d block;
    block << h_inv(iu, iu), h_inv(iu, iw), h_inv(iw, iu), h_inv(iw, iw);
    const double var = jac.dot(block * jac);
    if (!(var > 0.0)) continue;
    mean += std::polar(1.0 / var, std::atan2(w, u));
    out.gamma_information += 1.0 / var;
  }
  if (!(out.gamma_information > 0.0)) return out;
  out.gamma = std::arg(mean);
  const double c = std::cos(out.gamma), s = std::sin(out.gamma);
  for (int j = 0; j < n; ++j) {
    out.scales[segments[j].id] = c * x(2 + 2 * j) + s * x(3 + 2 * j);
  }
  out.ok = true;
  return out;
}

void MarginalisePlanarSegment(const PlanarSegmentView& segment, const PlanarFrame& frame,
                              PlanarSums* sums) {
  if (!frame.ok) return;
  const SegmentTerms t = TermsOf(segment, frame);
  if (!(t.nn > 0.0)) return;
  sums->h_marg -= (t.hu * t.hu.transpose() + t.hw * t.hw.transpose()) / t.nn;
  sums->g_marg -= (t.hu * t.bu + t.hw * t.bw) / t.nn;
  sums->c_marg -= (t.bu * t.bu + t.bw * t.bw) / t.nn;
}

Eigen::Quaterniond PlanarRotation(const PlanarFrame& frame, double gamma) {
  return Canonical((AxisAngle(frame.axis, gamma) * frame.align).normalized());
}

double TiltSignalToNoise(const PlanarSums& sums, const Eigen::Vector3d& axis,
                         const Eigen::Quaterniond& dq) {
  const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - axis * axis.transpose();
  const Eigen::Matrix3d r = dq.toRotationMatrix();
  const double signal = (p * sums.v00).trace();  // sum w |P v_0|^2
  const double noise = signal - 2.0 * (p * r * sums.v0i.transpose()).trace() +
                       (p * r * sums.vii * r.transpose()).trace();  // sum w |P (v_0 - dR v_i)|^2
  // Below 1e-12 of the rotation vectors' size (squared: 1e-24) is rounding, not tilt or noise.
  const double floor = 1e-24 * sums.v00.trace();
  if (!(signal > floor)) return 0.0;
  return std::sqrt(2.0 * signal / std::max(noise, floor));
}

}  // namespace rigcal::internal
