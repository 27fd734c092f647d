// SPDX-License-Identifier: Apache-2.0
// Target-based reference: the global reference pose model of thesis 4.2.
#include "rigcal/pattern/reference_calibration.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::pattern {
namespace {

// Chordal L2 mean of unit quaternions: the eigenvector of the largest eigenvalue of sum q q^T.
Eigen::Quaterniond MeanRotation(const std::vector<Eigen::Quaterniond>& qs,
                                const std::vector<bool>& keep) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  for (size_t k = 0; k < qs.size(); ++k) {
    if (!keep[k]) continue;
    const Eigen::Vector4d v = qs[k].coeffs();
    M += v * v.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(M);
  const Eigen::Vector4d v = eig.eigenvectors().col(3);
  const double sign = v[3] < 0.0 ? -1.0 : 1.0;  // w >= 0
  return Eigen::Quaterniond(sign * v[3], sign * v[0], sign * v[1], sign * v[2]).normalized();
}

}  // namespace

Expected<ReferenceEstimate> EstimateGlobalReference(const TimedTrajectory& master,
                                                    const TimedTrajectory& slave,
                                                    int64_t tolerance_ns) {
  std::vector<Eigen::Quaterniond> qs;
  std::vector<Eigen::Vector3d> cs;
  size_t j = 0;
  for (size_t k = 0; k < master.size(); ++k) {
    while (j < slave.size() && slave.t_ns[j] < master.t_ns[k] - tolerance_ns) ++j;
    if (j == slave.size()) break;
    if (std::llabs(slave.t_ns[j] - master.t_ns[k]) > tolerance_ns) continue;
    // dT = T_0^-1 T_i: the slave's pose in the master frame.
    const Pose& m = master.poses[k];
    const Pose& s = slave.poses[j];
    qs.push_back((m.q.conjugate() * s.q).normalized());
    cs.push_back(m.R().transpose() * (s.C - m.C));
  }
  if (qs.size() < 3) {
    return Error{"target reference: " + std::to_string(qs.size()) + " instants where both " +
                 master.name + " (" + std::to_string(master.size()) + " poses) and " + slave.name +
                 " (" + std::to_string(slave.size()) + " poses) see the target, need 3"};
  }
  const size_t n = qs.size();
  std::vector<bool> keep(n, true);
  // Robust start: the mean of all, then the deviations' median and MAD.
  Eigen::Quaterniond q_mean = MeanRotation(qs, keep);
  Eigen::Vector3d c_median;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values;
    values.reserve(cs.size());
    for (const auto& c : cs) values.push_back(c[axis]);
    c_median[axis] = Median(values);
  }
  std::vector<double> rot_dev(n);
  std::vector<double> pos_dev(n);
  for (size_t k = 0; k < n; ++k) {
    rot_dev[k] = q_mean.angularDistance(qs[k]);
    pos_dev[k] = (cs[k] - c_median).norm();
  }
  // Beyond median + 5 MAD, and beyond rounding: deviations under a nanoradian, or a billionth of
  // the positions' size, are double arithmetic, not an outlier (noiseless poses).
  const auto limit = [](const std::vector<double>& d, double floor) {
    const double med = Median(d);
    std::vector<double> abs_dev;
    abs_dev.reserve(d.size());
    for (double x : d) abs_dev.push_back(std::abs(x - med));
    return std::max(med + 5.0 * 1.4826 * Median(abs_dev), floor);
  };
  const double rot_limit = limit(rot_dev, 1e-9);
  const double pos_limit = limit(pos_dev, 1e-9 * (1.0 + c_median.norm()));
  ReferenceEstimate out;
  out.slave = slave.name;
  for (size_t k = 0; k < n; ++k) {
    keep[k] = rot_dev[k] <= rot_limit && pos_dev[k] <= pos_limit;
    if (!keep[k]) ++out.rejected;
  }
  q_mean = MeanRotation(qs, keep);
  Eigen::Vector3d c_mean = Eigen::Vector3d::Zero();
  int used = 0;
  for (size_t k = 0; k < n; ++k) {
    if (!keep[k]) continue;
    c_mean += cs[k];
    ++used;
  }
  c_mean /= used;
  Eigen::Vector3d rot_var = Eigen::Vector3d::Zero();
  Eigen::Vector3d pos_var = Eigen::Vector3d::Zero();
  double rot_sq = 0.0;
  double pos_sq = 0.0;
  for (size_t k = 0; k < n; ++k) {
    if (!keep[k]) continue;
    const Eigen::Vector3d r = RotationVector(q_mean.conjugate() * qs[k]);
    const Eigen::Vector3d p = cs[k] - c_mean;
    rot_var += r.cwiseAbs2();
    pos_var += p.cwiseAbs2();
    rot_sq += r.squaredNorm();
    pos_sq += p.squaredNorm();
  }
  const double dof = std::max(1, used - 1);
  out.master_from_slave.q = q_mean;
  out.master_from_slave.C = c_mean;
  out.master_from_slave.scale = 1.0;
  out.instants = used;
  out.rot_std_deg = std::sqrt(rot_var.maxCoeff() / dof / used) * kDegPerRad;
  out.pos_std = (pos_var / dof / used).cwiseSqrt();
  out.rot_spread_deg = std::sqrt(rot_sq / used) * kDegPerRad;
  out.pos_spread = std::sqrt(pos_sq / used);
  return out;
}

std::string FormatReference(const ReferenceEstimate& e, const std::string& unit) {
  const Similarity& s = e.master_from_slave;
  char line[640];
  std::snprintf(line, sizeof(line),
                "%s: q_wxyz [%.6f, %.6f, %.6f, %.6f]  C [%.6g, %.6g, %.6g] %s  |C| %.6g %s\n"
                "%s: σ rot %.4f deg, σ C [%.3g, %.3g, %.3g] %s (of the mean); spread per instant "
                "%.3f deg, %.3g %s; %d instants (%d rejected)\n",
                e.slave.c_str(), s.q.w(), s.q.x(), s.q.y(), s.q.z(), s.C.x(), s.C.y(), s.C.z(),
                unit.c_str(), s.C.norm(), unit.c_str(), e.slave.c_str(), e.rot_std_deg,
                e.pos_std.x(), e.pos_std.y(), e.pos_std.z(), unit.c_str(), e.rot_spread_deg,
                e.pos_spread, unit.c_str(), e.instants, e.rejected);
  return line;
}

}  // namespace rigcal::pattern
