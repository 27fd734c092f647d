// SPDX-License-Identifier: Apache-2.0
#include "online/pose_history.h"

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <deque>

#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// A pose's twist: the rotation vector ω and the translation's coordinates v in the group's
// exponential map, exp(ω, v) = [exp(ω) | V(ω) v].
struct Twist {
  Eigen::Vector3d omega;
  Eigen::Vector3d v;
};

Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return m;
}

// V(ω) = I + (1 - cos θ)/θ² ω^ + (θ - sin θ)/θ³ ω^², θ = |ω| (its series below 1e-4 rad).
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d w = Hat(omega);
  if (theta < 1e-4) return Eigen::Matrix3d::Identity() + 0.5 * w + (w * w) / 6.0;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * w +
         (theta - std::sin(theta)) / (t2 * theta) * (w * w);
}

// V(ω)⁻¹ = I - ω^/2 + (1 - θ sin θ / (2 (1 - cos θ)))/θ² ω^².
Eigen::Matrix3d InverseLeftJacobian(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d w = Hat(omega);
  if (theta < 1e-4) return Eigen::Matrix3d::Identity() - 0.5 * w + (w * w) / 12.0;
  const double t2 = theta * theta;
  const double c = (1.0 - theta * std::sin(theta) / (2.0 * (1.0 - std::cos(theta)))) / t2;
  return Eigen::Matrix3d::Identity() - 0.5 * w + c * (w * w);
}

Twist Log(const Pose& p) {
  const Eigen::Vector3d omega = RotationVector(p.q);
  return {omega, InverseLeftJacobian(omega) * p.C};
}

Pose Exp(const Twist& xi) {
  Pose p;
  const double theta = xi.omega.norm();
  p.q = theta > 0.0 ? AxisAngle(xi.omega, theta) : Eigen::Quaterniond::Identity();
  p.C = LeftJacobian(xi.omega) * xi.v;
  return p;
}

bool SameGroup(const HistorySet& a, const HistorySet& b, uint64_t stride) {
  return a.index / stride == b.index / stride && a.master_segment == b.master_segment &&
         a.slave_segment == b.slave_segment;
}

// `into` becomes the mean of its sets and `other`'s, each set weighted alike.
void Merge(const HistorySet& other, HistorySet* into) {
  const double w = static_cast<double>(other.sets) / (into->sets + other.sets);
  into->t_ns += std::llround(w * static_cast<double>(other.t_ns - into->t_ns));
  into->master = GroupMean(into->master, other.master, w);
  into->slave = GroupMean(into->slave, other.slave, w);
  into->sets += other.sets;
}

}  // namespace

Pose GroupMean(const Pose& a, const Pose& b, double weight_b) {
  const Twist xi = Log(a.Between(b));
  return a * Exp({weight_b * xi.omega, weight_b * xi.v});
}

void PoseHistory::Record(int capacity, const HistorySet& set) {
  if (capacity <= 0) return;
  if (!started_) {
    start_index_ = set.index;
    started_ = true;
  }
  if (!sets_.empty() && SameGroup(sets_.back(), set, stride_)) {
    Merge(set, &sets_.back());
  } else {
    sets_.push_back(set);
  }
  const auto groups = static_cast<uint64_t>(capacity);
  while (GroupsSinceStart(set.index) > groups) Coarsen();
  // Each change of scale segment splits a group: past the capacity even so, the oldest go.
  while (sets_.size() > groups) sets_.pop_front();
}

void PoseHistory::Restart() {
  sets_.clear();
  stride_ = 1;
  started_ = false;
}

uint64_t PoseHistory::GroupsSinceStart(uint64_t index) const {
  return index / stride_ - start_index_ / stride_ + 1;
}

// Doubles the stride: neighbours of one group at the new stride (and one scale segment each)
// become their mean.
void PoseHistory::Coarsen() {
  stride_ *= 2;
  std::deque<HistorySet> merged;
  for (const HistorySet& h : sets_) {
    if (!merged.empty() && SameGroup(merged.back(), h, stride_)) {
      Merge(h, &merged.back());
    } else {
      merged.push_back(h);
    }
  }
  sets_.swap(merged);
}

}  // namespace rigcal::internal
