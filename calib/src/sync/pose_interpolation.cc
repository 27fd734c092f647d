// SPDX-License-Identifier: Apache-2.0
// Interpolation of a trajectory at other instants (cameras that run free).
#include "rigcal/calib/pose_interpolation.h"

#include <algorithm>
#include <cmath>

namespace rigcal {

int64_t MedianInterval(const std::vector<int64_t>& t_ns) {
  if (t_ns.size() < 2) return 0;
  std::vector<int64_t> d(t_ns.size() - 1);
  for (size_t i = 0; i + 1 < t_ns.size(); ++i) d[i] = t_ns[i + 1] - t_ns[i];
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

std::optional<InterpolatedPose> InterpolatePose(const TimedTrajectory& trajectory, int64_t t_ns,
                                                int64_t max_gap_ns) {
  const auto& t = trajectory.t_ns;
  const auto it = std::lower_bound(t.begin(), t.end(), t_ns);
  if (it == t.end()) return std::nullopt;
  const auto hi = static_cast<size_t>(it - t.begin());
  auto segment_of = [&](size_t i) {
    return trajectory.segment.empty() ? 0 : trajectory.segment[i];
  };
  if (*it == t_ns) return InterpolatedPose{trajectory.poses[hi], segment_of(hi)};
  if (hi == 0) return std::nullopt;
  const size_t lo = hi - 1;
  if (t[hi] - t[lo] > max_gap_ns || segment_of(lo) != segment_of(hi)) return std::nullopt;
  InterpolatedPose out;
  out.segment = segment_of(lo);
  const bool cubic = lo > 0 && hi + 1 < t.size() && t[lo] - t[lo - 1] <= max_gap_ns &&
                     t[hi + 1] - t[hi] <= max_gap_ns && segment_of(lo - 1) == out.segment &&
                     segment_of(hi + 1) == out.segment;
  const size_t first = cubic ? lo - 1 : lo;
  out.pose = InterpolateAround(&t[first], &trajectory.poses[first], cubic ? 4 : 2, t_ns);
  return out;
}

Pose InterpolateAround(const int64_t* t, const Pose* poses, int count, int64_t t_ns) {
  Pose out;
  if (count != 4) {
    const double f = static_cast<double>(t_ns - t[0]) / static_cast<double>(t[1] - t[0]);
    out.q = poses[0].q.slerp(f, poses[1].q).normalized();
    out.C = (1.0 - f) * poses[0].C + f * poses[1].C;
    return out;
  }
  // Cubic Lagrange through the four poses: the centre directly, the rotation as rotation
  // vectors in the tangent space of pose 1 (the last one before t_ns).
  const Pose& a = poses[1];
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (int i = 0; i < 4; ++i) {
    double w = 1.0;
    for (int m = 0; m < 4; ++m) {
      if (m == i) continue;
      w *= static_cast<double>(t_ns - t[m]) / static_cast<double>(t[i] - t[m]);
    }
    c += w * poses[i].C;
    const Eigen::AngleAxisd rel(a.q.conjugate() * poses[i].q);
    v += w * rel.angle() * rel.axis();
  }
  out.C = c;
  out.q = v.norm() > 0.0
              ? (a.q * Eigen::Quaterniond(Eigen::AngleAxisd(v.norm(), v.normalized()))).normalized()
              : a.q;
  return out;
}

}  // namespace rigcal
