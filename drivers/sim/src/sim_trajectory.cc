// SPDX-License-Identifier: Apache-2.0
#include "sim_trajectory.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace rigcal::sim::internal {
namespace {

// Rotation vector of q (angle <= pi).
Eigen::Vector3d Log(const Eigen::Quaterniond& q) {
  Eigen::Quaterniond c = q.w() < 0 ? Eigen::Quaterniond(-q.w(), -q.x(), -q.y(), -q.z()) : q;
  const double n = c.vec().norm();
  if (n < 1e-12) return 2.0 * c.vec();
  return 2.0 * std::atan2(n, c.w()) / n * c.vec();
}

Eigen::Quaterniond Exp(const Eigen::Vector3d& w) {
  const double angle = w.norm();
  if (angle < 1e-12) return Eigen::Quaterniond(1.0, 0.5 * w.x(), 0.5 * w.y(), 0.5 * w.z());
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
}

}  // namespace

Trajectory Trajectory::FromWaypoints(const std::vector<Pose>& waypoints, double interval_s) {
  Trajectory t;
  t.spline_ = true;
  t.interval_s_ = interval_s;
  const size_t n = waypoints.size();
  t.duration_s_ = static_cast<double>(n - 1) * interval_s;
  t.control_.reserve(n + 2);
  // Phantom before: reflect waypoint 1 about waypoint 0 (position and rotation), which makes
  // the curve start exactly at waypoint 0; likewise at the end.
  auto reflect = [](const Pose& a, const Pose& b) {
    Pose p;
    p.C = 2.0 * a.C - b.C;
    p.q = (a.q * Exp(-Log(a.q.conjugate() * b.q))).normalized();
    return p;
  };
  t.control_.push_back(reflect(waypoints[0], waypoints[1]));
  for (const Pose& w : waypoints) t.control_.push_back(w);
  t.control_.push_back(reflect(waypoints[n - 1], waypoints[n - 2]));
  return t;
}

Trajectory Trajectory::FromSamples(const std::vector<int64_t>& t_ns, const std::vector<Pose>& poses,
                                   const Pose& body_from_master) {
  Trajectory t;
  t.spline_ = false;
  t.body_from_master_ = body_from_master;
  t.t_s_.reserve(t_ns.size());
  for (int64_t stamp : t_ns) t.t_s_.push_back(static_cast<double>(stamp - t_ns.front()) * 1e-9);
  t.samples_ = poses;
  t.duration_s_ = t.t_s_.back();
  return t;
}

Pose Trajectory::At(double t_s) const {
  t_s = std::clamp(t_s, 0.0, duration_s_);
  if (!spline_) {
    const auto it = std::upper_bound(t_s_.begin(), t_s_.end(), t_s);
    size_t i = it == t_s_.begin() ? 0 : static_cast<size_t>(it - t_s_.begin()) - 1;
    i = std::min(i, samples_.size() - 2);
    const double a = std::clamp((t_s - t_s_[i]) / (t_s_[i + 1] - t_s_[i]), 0.0, 1.0);
    Pose body;
    body.C = (1.0 - a) * samples_[i].C + a * samples_[i + 1].C;
    body.q = samples_[i].q.slerp(a, samples_[i + 1].q).normalized();
    return body * body_from_master_;
  }
  const double s = t_s / interval_s_;
  const int segments = static_cast<int>(control_.size()) - 3;
  const int j = std::clamp(static_cast<int>(std::floor(s)), 0, segments - 1);
  const double u = s - j;
  const double u2 = u * u, u3 = u2 * u;
  const double b0 = (1 - u) * (1 - u) * (1 - u) / 6.0;
  const double b1 = (3 * u3 - 6 * u2 + 4) / 6.0;
  const double b2 = (-3 * u3 + 3 * u2 + 3 * u + 1) / 6.0;
  const double b3 = u3 / 6.0;
  const Pose& c0 = control_[j];
  const Pose& c1 = control_[j + 1];
  const Pose& c2 = control_[j + 2];
  const Pose& c3 = control_[j + 3];
  Pose out;
  out.C = b0 * c0.C + b1 * c1.C + b2 * c2.C + b3 * c3.C;
  // Cumulative basis for the rotation (Kim et al. 1995): R = R0 prod Exp(~b_k Log(R_{k-1}^T R_k)).
  const double cb1 = b1 + b2 + b3, cb2 = b2 + b3, cb3 = b3;
  out.q = (c0.q * Exp(cb1 * Log(c0.q.conjugate() * c1.q)) *
           Exp(cb2 * Log(c1.q.conjugate() * c2.q)) * Exp(cb3 * Log(c2.q.conjugate() * c3.q)))
              .normalized();
  return out;
}

}  // namespace rigcal::sim::internal
