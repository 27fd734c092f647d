// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/error_model.h"

#include <cmath>

#include "rigcal/base/quaternion.h"

namespace rigcal {
namespace {

double AngleBetweenVectors(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double na = a.norm(), nb = b.norm();
  if (na == 0.0 || nb == 0.0) return 0.0;
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

}  // namespace

CalibrationError CompareToTruth(const Similarity& estimate, const Similarity& truth,
                                const Eigen::Vector3d& axis) {
  CalibrationError e;
  e.rot_deg = AngleBetween(estimate.q, truth.q) * kDegPerRad;
  e.dir_deg = AngleBetweenVectors(truth.C, estimate.C) * kDegPerRad;
  const double n = truth.C.norm();
  e.dist_pct = n > 0.0 ? std::abs(n - estimate.C.norm()) / n * 100.0 : 0.0;
  e.trans_err = (truth.C - estimate.C).norm();
  e.scale_pct = std::abs(truth.scale - estimate.scale) / std::abs(truth.scale) * 100.0;
  if (axis.norm() > 0.0) {
    const Eigen::Vector3d a = axis.normalized();
    const Eigen::Vector3d d = estimate.C - truth.C;
    e.axis_err = std::abs(d.dot(a));
    e.plane_err = (d - d.dot(a) * a).norm();
  }
  return e;
}

ConstraintResidual ResidualOf(const RigMotion& motion, const Similarity& rig) {
  ConstraintResidual r;
  const Eigen::Quaterniond lhs = motion.master.q * rig.q;  // R_0 dR
  const Eigen::Quaterniond rhs = rig.q * motion.slave.q;   // dR R_i
  r.rotation_deg = AngleBetween(lhs, rhs) * kDegPerRad;
  const Eigen::Vector3d p_lhs = motion.master.q * rig.C + motion.master.C;  // R_0 dC + C_0
  const Eigen::Vector3d p_rhs = rig.scale * (rig.q * motion.slave.C) + rig.C;
  r.position_dir_deg = AngleBetweenVectors(p_lhs, p_rhs) * kDegPerRad;
  r.position_abs = (p_lhs - p_rhs).norm();
  const Eigen::Quaterniond q0 = Canonical(motion.master.q);
  Eigen::Quaterniond qi = Canonical(motion.slave.q);
  const double v0 = q0.vec().norm(), vi = qi.vec().norm();
  if (v0 > 1e-9 && vi > 1e-9) {
    r.master_axis_dot = motion.master.C.dot(q0.vec() / v0);
    r.slave_axis_dot = motion.slave.C.dot(qi.vec() / vi);
    if (std::abs(r.slave_axis_dot) > 1e-12) {
      r.measured_scale = r.master_axis_dot / r.slave_axis_dot;  // (4.18)
      r.scale_pct = std::abs(rig.scale - r.measured_scale) / std::abs(rig.scale) * 100.0;
    }
  }
  return r;
}

double ScaleDotEpsilon(double configured, const std::vector<Eigen::Vector3d>& slave_translations) {
  if (configured > 0.0) return configured;
  if (slave_translations.empty()) return 0.0;
  double sum = 0.0;
  for (const Eigen::Vector3d& c : slave_translations) sum += c.squaredNorm();
  return 1e-3 * std::sqrt(sum / static_cast<double>(slave_translations.size()));
}

}  // namespace rigcal
