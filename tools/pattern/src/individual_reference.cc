// SPDX-License-Identifier: Apache-2.0
// Target-based reference: the individual reference pose model of thesis 4.2 (fig. 4.4).
#include "rigcal/pattern/individual_reference.h"

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::pattern {
namespace {

Eigen::Quaterniond RotationExp(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle < 1e-15) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle));
}

// One instant: T_0 dT = W T_i (4.2, individual reference poses), with dR = dR0 exp(d_rot),
// R_W = R_W0 exp(w_rot); residual: log((R_0 dR)^T R_W R_i) / sigma_rot and
// (R_0 dC + C_0 - R_W C_i - t_W) / sigma_pos.
struct InstantResidual {
  InstantResidual(const Pose& master, const Pose& slave, const Eigen::Quaterniond& d_rot0,
                  const Eigen::Quaterniond& w_rot0, double sigma_rot, double sigma_pos)
      : master_(master),
        slave_(slave),
        d_rot0_(d_rot0),
        w_rot0_(w_rot0),
        sigma_rot_(sigma_rot),
        sigma_pos_(sigma_pos) {}

  template <typename T>
  bool operator()(const T* d_rot, const T* d_c, const T* w_rot, const T* w_t, T* r) const {
    using Q = Eigen::Quaternion<T>;
    using V = Eigen::Matrix<T, 3, 1>;
    T qd[4];
    T qw[4];
    ceres::AngleAxisToQuaternion(d_rot, qd);  // w, x, y, z
    ceres::AngleAxisToQuaternion(w_rot, qw);
    const Q dq = d_rot0_.cast<T>() * Q(qd[0], qd[1], qd[2], qd[3]);
    const Q wq = w_rot0_.cast<T>() * Q(qw[0], qw[1], qw[2], qw[3]);
    const Q lhs = master_.q.cast<T>() * dq;
    const Q rhs = wq * slave_.q.cast<T>();
    const Q e = lhs.conjugate() * rhs;
    const T qe[4] = {e.w(), e.x(), e.y(), e.z()};
    T log_e[3];
    ceres::QuaternionToAngleAxis(qe, log_e);
    const V c_lhs = master_.q.cast<T>() * V(d_c[0], d_c[1], d_c[2]) + master_.C.cast<T>();
    const V c_rhs = wq * slave_.C.cast<T>() + V(w_t[0], w_t[1], w_t[2]);
    for (int a = 0; a < 3; ++a) {
      r[a] = log_e[a] / sigma_rot_;
      r[3 + a] = (c_lhs[a] - c_rhs[a]) / sigma_pos_;
    }
    return true;
  }

  Pose master_;
  Pose slave_;
  Eigen::Quaterniond d_rot0_;
  Eigen::Quaterniond w_rot0_;
  double sigma_rot_;
  double sigma_pos_;
};

struct Pair {
  Pose master;
  Pose slave;
};

// Rotation and centre residual of one instant under (dT, W).
void Residual(const Pair& p, const Pose& d, const Pose& w, double* rot, double* pos) {
  const Pose lhs = p.master * d;
  const Pose rhs = w * p.slave;
  *rot = lhs.q.angularDistance(rhs.q);
  *pos = (lhs.C - rhs.C).norm();
}

// W from dT: the chordal mean of T_0 dT T_i^-1 over the kept instants.
Pose MeanTargetPose(const std::vector<Pair>& pairs, const std::vector<bool>& keep, const Pose& d) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  int n = 0;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!keep[k]) continue;
    const Pose w = pairs[k].master * d * pairs[k].slave.Inverse();
    const Eigen::Vector4d v = w.q.coeffs();
    M += v * v.transpose();
    t += w.C;
    ++n;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(M);
  const Eigen::Vector4d v = eig.eigenvectors().col(3);
  Pose w;
  w.q = Eigen::Quaterniond(v[3], v[0], v[1], v[2]).normalized();
  w.C = t / std::max(1, n);
  return w;
}

// The instants where both cameras see their target (stamps within tolerance_ns).
std::vector<Pair> MatchInstants(const TimedTrajectory& master, const TimedTrajectory& slave,
                                int64_t tolerance_ns) {
  std::vector<Pair> pairs;
  size_t j = 0;
  for (size_t k = 0; k < master.size(); ++k) {
    while (j < slave.size() && slave.t_ns[j] < master.t_ns[k] - tolerance_ns) ++j;
    if (j == slave.size()) break;
    if (std::llabs(slave.t_ns[j] - master.t_ns[k]) > tolerance_ns) continue;
    pairs.push_back({master.poses[k], slave.poses[j]});
  }
  return pairs;
}

// The linear start: dR from the motions relative to the first instant (A dT = dT B; Kabsch on
// the rotation vectors, Park & Martin), then dC from (R_A - I) dC = dR C_B - C_A. Errors when
// the cameras rotated about one axis only.
Expected<Pose> LinearSlavePose(const std::vector<Pair>& pairs, const std::string& who) {
  const size_t n = pairs.size();
  Eigen::Matrix3Xd alpha(3, n - 1);
  Eigen::Matrix3Xd beta(3, n - 1);
  std::vector<Pose> a(n - 1);
  std::vector<Pose> b(n - 1);
  for (size_t k = 1; k < n; ++k) {
    a[k - 1] = pairs[0].master.Between(pairs[k].master);
    b[k - 1] = pairs[0].slave.Between(pairs[k].slave);
    alpha.col(static_cast<Eigen::Index>(k - 1)) = RotationVector(a[k - 1].q);
    beta.col(static_cast<Eigen::Index>(k - 1)) = RotationVector(b[k - 1].q);
  }
  const Eigen::Matrix3d H = beta * alpha.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Eigen::Matrix3d dR = svd.matrixV() * D * svd.matrixU().transpose();
  // Two rotation axes: the second principal spread of the rotation vectors against their noise.
  const Eigen::JacobiSVD<Eigen::Matrix3Xd> axes(alpha);
  const double second_spread = axes.singularValues()[1] / std::sqrt(double(n - 1));
  const double axis_noise = std::sqrt((alpha - dR * beta).squaredNorm() / (3.0 * double(n - 1)));
  if (!(second_spread > 10.0 * axis_noise) || second_spread < 1e-6) {
    return Error{who + ": the cameras rotated about one axis only (second rotation spread " +
                 std::to_string(second_spread * kDegPerRad) + " deg against " +
                 std::to_string(axis_noise * kDegPerRad) +
                 " deg noise): the slave's position along it is not determined; tilt the rig "
                 "about a second axis"};
  }
  Eigen::MatrixXd L(3 * (n - 1), 3);
  Eigen::VectorXd y(3 * (n - 1));
  for (size_t k = 0; k + 1 < n; ++k) {
    const auto row = static_cast<Eigen::Index>(3 * k);
    L.block<3, 3>(row, 0) = a[k].R() - Eigen::Matrix3d::Identity();
    y.segment<3>(row) = dR * b[k].C - a[k].C;
  }
  Pose d;
  d.q = Eigen::Quaterniond(dR).normalized();
  d.C = L.colPivHouseholderQr().solve(y);
  return d;
}

// RMS per component of the residuals `r` of the kept instants (at least 1e-9).
double KeptRms(const std::vector<double>& r, const std::vector<bool>& keep) {
  double sq = 0.0;
  int m = 0;
  for (size_t k = 0; k < r.size(); ++k) {
    if (!keep[k]) continue;
    sq += r[k] * r[k];
    ++m;
  }
  return std::max(std::sqrt(sq / (3.0 * m)), 1e-9);
}

// Drops the outlier instants: whitened residual beyond median + 5 * 1.4826 * MAD.
void DropOutlierInstants(const std::vector<double>& rot, const std::vector<double>& pos,
                         std::vector<bool>* keep) {
  const size_t n = rot.size();
  const double sr = KeptRms(rot, *keep);
  const double sp = KeptRms(pos, *keep);
  std::vector<double> score(n);
  for (size_t k = 0; k < n; ++k) score[k] = std::hypot(rot[k] / sr, pos[k] / sp);
  const double med = Median(score);
  std::vector<double> dev;
  dev.reserve(score.size());
  for (double s : score) dev.push_back(std::abs(s - med));
  // Scores are in units of the residuals' RMS: within 3 of it is never an outlier (with
  // noiseless poses the RMS is rounding, and the spread of the scores means nothing).
  const double limit = std::max(med + 5.0 * 1.4826 * Median(dev), 3.0);
  for (size_t k = 0; k < n; ++k) (*keep)[k] = score[k] <= limit;
}

// One refinement round's outcome: the covariance of (d_rot, dC) and the residuals' RMS.
struct RefinedRound {
  Eigen::Matrix3d rot_cov = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d pos_cov = Eigen::Matrix3d::Zero();
  double rot_rms = 0.0;
  double pos_rms = 0.0;
};

// Least squares of every kept instant's residual (InstantResidual) over dT and W, weighted by
// the residuals' RMS under the current estimate; updates *d and *w.
Expected<RefinedRound> RefineInstants(const std::vector<Pair>& pairs,
                                      const std::vector<bool>& keep, double sigma_rot,
                                      double sigma_pos, Pose* d, Pose* w, const std::string& who) {
  double d_rot[3] = {0, 0, 0};
  double d_c[3] = {d->C.x(), d->C.y(), d->C.z()};
  double w_rot[3] = {0, 0, 0};
  double w_t[3] = {w->C.x(), w->C.y(), w->C.z()};
  ceres::Problem problem;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!keep[k]) continue;
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<InstantResidual, 6, 3, 3, 3, 3>(
            new InstantResidual(pairs[k].master, pairs[k].slave, d->q, w->q, sigma_rot, sigma_pos)),
        nullptr, d_rot, d_c, w_rot, w_t);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 50;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable()) {
    return Error{who + ": the least-squares refinement failed: " + summary.message};
  }
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  cov_options.null_space_rank = 0;
  ceres::Covariance covariance(cov_options);
  const std::vector<std::pair<const double*, const double*>> blocks = {
      {d_rot, d_rot}, {d_c, d_c}, {d_rot, d_c}};
  const bool cov_ok = covariance.Compute(blocks, &problem);
  d->q = (d->q * RotationExp(Eigen::Vector3d(d_rot[0], d_rot[1], d_rot[2]))).normalized();
  d->C = Eigen::Vector3d(d_c[0], d_c[1], d_c[2]);
  w->q = (w->q * RotationExp(Eigen::Vector3d(w_rot[0], w_rot[1], w_rot[2]))).normalized();
  w->C = Eigen::Vector3d(w_t[0], w_t[1], w_t[2]);
  if (!cov_ok) {
    return Error{who +
                 ": the covariance is singular: the motion does not determine the "
                 "slave's pose (rotate the rig about two different axes)"};
  }
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> c_rot;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> c_pos;
  covariance.GetCovarianceBlock(d_rot, d_rot, c_rot.data());
  covariance.GetCovarianceBlock(d_c, d_c, c_pos.data());
  RefinedRound round;
  round.rot_cov = c_rot;
  round.pos_cov = c_pos;
  round.rot_rms = sigma_rot;
  round.pos_rms = sigma_pos;
  return round;
}

}  // namespace

Expected<IndividualReference> EstimateIndividualReference(const TimedTrajectory& master,
                                                          const TimedTrajectory& slave,
                                                          int64_t tolerance_ns) {
  const std::vector<Pair> pairs = MatchInstants(master, slave, tolerance_ns);
  const size_t n = pairs.size();
  const std::string who = "individual target reference " + master.name + "/" + slave.name;
  if (n < 4) {
    return Error{who + ": " + std::to_string(n) + " instants where both cameras see their " +
                 "target (stamps within " + std::to_string(tolerance_ns / 1e6) + " ms), need 4"};
  }
  auto linear = LinearSlavePose(pairs, who);
  if (!linear) return Error{linear.error()};
  Pose d = *linear;
  std::vector<bool> keep(n, true);
  Pose w = MeanTargetPose(pairs, keep, d);
  RefinedRound refined;
  for (int round = 0; round < 2; ++round) {
    // Residuals under the current estimate; from the second round on, outlier instants are
    // dropped first.
    std::vector<double> rot(n);
    std::vector<double> pos(n);
    for (size_t k = 0; k < n; ++k) Residual(pairs[k], d, w, &rot[k], &pos[k]);
    if (round == 1) DropOutlierInstants(rot, pos, &keep);
    auto result = RefineInstants(pairs, keep, KeptRms(rot, keep), KeptRms(pos, keep), &d, &w, who);
    if (!result) return Error{result.error()};
    refined = *result;
  }
  IndividualReference out;
  ReferenceEstimate& e = out.estimate;
  e.slave = slave.name;
  int used = 0;
  for (bool k : keep) used += k ? 1 : 0;
  e.master_from_slave.q = d.q;
  e.master_from_slave.C = d.C;
  e.master_from_slave.scale = 1.0;
  e.instants = used;
  e.rejected = static_cast<int>(n) - used;
  // The rotation's covariance is that of a right perturbation: its largest axis in degrees.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> rot_eig(refined.rot_cov);
  e.rot_std_deg = std::sqrt(std::max(0.0, rot_eig.eigenvalues()[2])) * kDegPerRad;
  e.pos_std = refined.pos_cov.diagonal().cwiseMax(0.0).cwiseSqrt();
  e.rot_spread_deg = refined.rot_rms * std::sqrt(3.0) * kDegPerRad;
  e.pos_spread = refined.pos_rms * std::sqrt(3.0);
  out.master_target_from_slave_target = w;
  return out;
}

}  // namespace rigcal::pattern
