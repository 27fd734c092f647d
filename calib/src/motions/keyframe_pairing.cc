// SPDX-License-Identifier: Apache-2.0
// Keyframes and motion pairs of the recursive estimator (keyframe_pairing.h).
#include "motions/keyframe_pairing.h"

#include <Eigen/Core>
#include <cmath>

#include "rigcal/base/quaternion.h"

namespace rigcal::internal {

bool OfferKeyframe(const RigEstimatorOptions& o, double min_translation, int64_t t_ns,
                   const CameraPose& master, const CameraPose& slave,
                   std::deque<Keyframe>* keyframes) {
  if (!keyframes->empty() && keyframes->back().segment != slave.segment) {
    keyframes->clear();  // pairs never cross a scale segment
  }
  if (!keyframes->empty()) {
    const Keyframe& last = keyframes->back();
    const double angle = AngleBetween(last.master.q, master.pose.q) * kDegPerRad;
    const double trans = (master.pose.C - last.master.C).norm();
    if (angle < o.keyframe_min_angle_deg && trans < min_translation &&
        t_ns - last.t_ns < o.keyframe_max_interval_ns) {
      return false;
    }
  }
  keyframes->push_back({t_ns, master.pose, slave.pose, slave.segment});
  if (static_cast<int>(keyframes->size()) > o.keyframe_history) keyframes->pop_front();
  return true;
}

std::optional<KeyframePair> PairNewestKeyframe(const RigEstimatorOptions& o,
                                               const std::deque<Keyframe>& keyframes) {
  if (keyframes.size() < 2) return std::nullopt;
  const Keyframe& b = keyframes.back();
  Eigen::Vector3d lo = b.master.C, hi = b.master.C;
  for (const auto& k : keyframes) {
    lo = lo.cwiseMin(k.master.C);
    hi = hi.cwiseMax(k.master.C);
  }
  const double target_trans = o.pair_target_translation_fraction * (hi - lo).norm();
  const double target_angle = o.pair_target_angle_deg * kRadPerDeg;
  int chosen = -1;
  for (int j = static_cast<int>(keyframes.size()) - 2; j >= 0; --j) {
    const Keyframe& a = keyframes[j];
    if (b.t_ns - a.t_ns > o.pair_max_span_ns) break;
    chosen = j;
    if (AngleBetween(a.master.q, b.master.q) >= target_angle ||
        (b.master.C - a.master.C).norm() >= target_trans) {
      break;
    }
  }
  if (chosen < 0) return std::nullopt;
  const Keyframe& a = keyframes[chosen];
  KeyframePair pair;
  pair.motion.master = a.master.Between(b.master);
  pair.motion.slave = a.slave.Between(b.slave);
  pair.motion.segment = b.segment;
  pair.motion.t_a_ns = a.t_ns;
  pair.motion.t_b_ns = b.t_ns;
  pair.span_keyframes = static_cast<double>(keyframes.size() - 1 - chosen);
  const Keyframe& p = keyframes[keyframes.size() - 2];
  pair.consecutive_angle_diff_deg =
      std::abs(AngleBetween(p.master.q, b.master.q) - AngleBetween(p.slave.q, b.slave.q)) *
      kDegPerRad;
  return pair;
}

}  // namespace rigcal::internal
