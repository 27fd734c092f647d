// SPDX-License-Identifier: Apache-2.0
#include "motions/motion_data.h"

#include "rigcal/base/quaternion.h"

namespace rigcal::internal {

std::vector<MotionData> ToMotionData(const std::vector<RigMotion>& motions) {
  std::vector<MotionData> out;
  out.reserve(motions.size());
  for (const auto& m : motions) {
    MotionData d;
    d.q0 = ToWxyz(m.master.q.normalized());
    d.qi = ToWxyz(m.slave.q.normalized());
    d.R0 = m.master.q.normalized().toRotationMatrix();
    d.C0 = m.master.C;
    d.Ci = m.slave.C;
    d.angle0 = RotationAngle(m.master.q);
    d.anglei = RotationAngle(m.slave.q);
    d.segment = m.segment;
    d.t_ns = m.t_a_ns + (m.t_b_ns - m.t_a_ns) / 2;
    d.t_a_ns = m.t_a_ns;
    d.t_b_ns = m.t_b_ns;
    d.duration_ns = m.t_b_ns - m.t_a_ns;
    out.push_back(d);
  }
  AlignSignsCanonical(&out);
  return out;
}

void AlignSignsCanonical(std::vector<MotionData>* motions) {
  for (auto& m : *motions) {
    if (m.q0[0] < 0.0) m.q0 = -m.q0;
    if (m.qi[0] < 0.0) m.qi = -m.qi;
  }
}

void AlignSignsWith(const Eigen::Vector4d& dq, std::vector<MotionData>* motions) {
  for (auto& m : *motions) {
    const Eigen::Vector4d lhs = LeftMultiplicationMatrix(m.q0) * dq;
    const Eigen::Vector4d rhs = LeftMultiplicationMatrix(dq) * m.qi;  // dq · qi
    if ((lhs - rhs).squaredNorm() > (lhs + rhs).squaredNorm()) m.qi = -m.qi;
  }
}

}  // namespace rigcal::internal
