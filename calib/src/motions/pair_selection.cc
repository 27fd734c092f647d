// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/pair_selection.h"

#include <algorithm>
#include <cmath>

#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal {
namespace {

double TrajectoryExtent(const std::vector<Pose>& poses) {
  if (poses.empty()) return 0.0;
  Eigen::Vector3d lo = poses.front().C, hi = poses.front().C;
  for (const auto& p : poses) {
    lo = lo.cwiseMin(p.C);
    hi = hi.cwiseMax(p.C);
  }
  return (hi - lo).norm();
}

std::vector<IndexPair> SinceStartPairs(const RigRecording& rec) {
  std::vector<IndexPair> pairs;
  const int n = static_cast<int>(rec.size());
  for (int b = 1; b < n; ++b) {
    if (rec.master.SegmentAt(b) == rec.master.SegmentAt(0)) pairs.push_back({0, b});
  }
  return pairs;
}

// Whether poses a and b lie in the same segment of the master and of every slave (a pair
// across a slave's re-initialisation would be lost for that slave).
bool SameSegments(const RigRecording& rec, int a, int b) {
  if (rec.master.SegmentAt(a) != rec.master.SegmentAt(b)) return false;
  for (const auto& slave : rec.slaves) {
    if (slave.SegmentAt(a) != slave.SegmentAt(b)) return false;
  }
  return true;
}

std::vector<IndexPair> WalkPairs(const RigRecording& rec, const PairOptions& opt) {
  std::vector<IndexPair> pairs;
  const int n = static_cast<int>(rec.size());
  if (n < 2) return pairs;
  const auto& poses = rec.master.poses;
  const double extent = std::max(TrajectoryExtent(poses), 1e-300);
  const double target_angle = opt.target_angle_deg * kRadPerDeg;
  const double target_trans = opt.target_translation_fraction * extent;
  const double min_angle = opt.min_angle_deg * kRadPerDeg;
  const double min_trans = opt.min_translation_fraction * extent;
  const int max_span = std::max(1, static_cast<int>(opt.max_span_fraction * n));
  const int stride = std::max(1, (n + opt.max_pairs - 1) / opt.max_pairs);

  // At most max_pairs_per_end pairs end at one pose (0 = no limit): walks from neighbouring
  // anchors often stop at the same pose (the end of a turn, the end of the recording), and
  // that pose's noise enters all of their motions alike. A taken end moves on to the next
  // free pose (the motion only grows), within the span limit and the segment.
  std::vector<int> end_uses(n, 0);
  auto taken = [&](int b) {
    return opt.max_pairs_per_end > 0 && end_uses[b] >= opt.max_pairs_per_end;
  };
  // A walk that runs into the end of the recording (or of a segment) before it reaches a
  // target or the span limit stops at that last pose, and so do the walks of every later
  // anchor: one pose's noise would enter a large share of the motions (half of them when the
  // span limit is half the recording). Only one such truncated pair ends at a pose.
  std::vector<bool> truncated_end(n, false);
  for (int a = 0; a + 1 < n; a += stride) {
    int chosen = -1;
    bool complete = false;
    for (int b = a + 1; b < n && b - a <= max_span; ++b) {
      if (!SameSegments(rec, a, b)) break;
      chosen = b;
      if (AngleBetween(poses[a].q, poses[b].q) >= target_angle ||
          (poses[b].C - poses[a].C).norm() >= target_trans || b - a == max_span) {
        complete = true;
        break;
      }
    }
    if (chosen > 0 && !complete) {
      if (truncated_end[chosen]) continue;
      truncated_end[chosen] = true;
    }
    while (chosen > 0 && taken(chosen)) {
      const int next = chosen + 1;
      chosen = next < n && next - a <= max_span && SameSegments(rec, a, next) ? next : -1;
    }
    if (chosen < 0) continue;
    const double angle = AngleBetween(poses[a].q, poses[chosen].q);
    const double trans = (poses[chosen].C - poses[a].C).norm();
    if (angle >= min_angle || trans >= min_trans) {
      pairs.push_back({a, chosen});
      ++end_uses[chosen];
    }
  }
  return pairs;
}

// Scale-free noise of the motions of one span: the rotation angles of master and slave motion
// must be equal, so the spread of their difference measures the pose noise plus the drift
// accumulated over the span, while the master angle measures the signal.
struct SpanFigures {
  double median_angle = 0.0;  // radians
  double noise = 0.0;         // 1.4826 MAD of (master angle - slave angle), radians
};

SpanFigures MeasureSpan(const RigRecording& rec, int span, int samples) {
  const int n = static_cast<int>(rec.size());
  const int stride = std::max(1, (n - span) / samples);
  std::vector<double> angles, diffs;
  for (int a = 0; a + span < n; a += stride) {
    if (rec.master.SegmentAt(a) != rec.master.SegmentAt(a + span)) continue;
    const double angle = AngleBetween(rec.master.poses[a].q, rec.master.poses[a + span].q);
    angles.push_back(angle);
    for (const auto& slave : rec.slaves) {
      if (slave.SegmentAt(a) != slave.SegmentAt(a + span)) continue;
      diffs.push_back(angle - AngleBetween(slave.poses[a].q, slave.poses[a + span].q));
    }
  }
  SpanFigures f;
  if (angles.empty()) return f;
  f.median_angle = MedianAndSigma(angles).median;
  if (!diffs.empty()) f.noise = MedianAndSigma(diffs).sigma;
  return f;
}

}  // namespace

std::vector<IndexPair> RelativePairs(const RigRecording& rec, int span, int stride) {
  std::vector<IndexPair> pairs;
  const int n = static_cast<int>(rec.size());
  for (int a = 0; a + span < n; a += std::max(stride, 1)) {
    if (rec.master.SegmentAt(a) == rec.master.SegmentAt(a + span)) pairs.push_back({a, a + span});
  }
  return pairs;
}

std::vector<int> AutoSpanCandidates(int poses, const PairOptions& options) {
  const int longest = std::max(1, static_cast<int>(options.auto_max_span_fraction * poses));
  std::vector<int> spans;
  for (int span = 1; span <= longest;) {
    spans.push_back(span);
    span = std::max(span + 1, static_cast<int>(std::lround(span * 1.5)));
  }
  return spans;
}

int AutoPairSpan(const RigRecording& recording, const PairOptions& options) {
  const int n = static_cast<int>(recording.size());
  const int max_span = std::max(1, static_cast<int>(options.max_span_fraction * n));
  const double cap = options.target_angle_deg * kRadPerDeg;
  int best_span = 0;
  double best_score = 0.0, best_angle = 0.0;
  for (int span = 1; span <= max_span && span < n; span *= 2) {
    const SpanFigures f = MeasureSpan(recording, span, 200);
    // Signal to noise of the span's motions; angles beyond the cap add no information
    // (and approach the 180-degree sign ambiguity).
    const double score = std::min(f.median_angle, cap) / std::max(f.noise, 1e-6);
    if (score > best_score) {
      best_score = score;
      best_span = span;
      best_angle = f.median_angle;
    }
  }
  if (best_angle < options.min_angle_deg * kRadPerDeg) return 0;  // no rotation to speak of
  return best_span;
}

std::vector<IndexPair> SelectPairs(const RigRecording& recording, const PairOptions& options) {
  switch (options.policy) {
    case PairOptions::Policy::kSinceStart:
      return SinceStartPairs(recording);
    case PairOptions::Policy::kRelative:
      return RelativePairs(recording, options.step);
    case PairOptions::Policy::kAuto:  // chosen per slave by CalibrateRig; here kWalk's
    case PairOptions::Policy::kGls:
    case PairOptions::Policy::kWalk: {
      // Walk to the target angle, but not beyond the spans whose motions are still better
      // than noise (twice the best span).
      PairOptions walk = options;
      const int span = AutoPairSpan(recording, options);
      const int n = static_cast<int>(recording.size());
      if (span > 0 && n > 0) {
        walk.max_span_fraction = std::min(options.max_span_fraction, std::max(2.0 * span, 2.0) / n);
      }
      return WalkPairs(recording, walk);
    }
  }
  return {};
}

std::vector<RigMotion> MotionsForSlave(const RigRecording& recording, int slave_index,
                                       const std::vector<IndexPair>& pairs) {
  std::vector<RigMotion> motions;
  const CameraTrack& slave = recording.slaves.at(slave_index);
  motions.reserve(pairs.size());
  for (const auto& p : pairs) {
    const int seg = slave.SegmentAt(p.a);
    if (slave.SegmentAt(p.b) != seg) continue;
    RigMotion m;
    m.master = recording.master.poses[p.a].Between(recording.master.poses[p.b]);
    m.slave = slave.poses[p.a].Between(slave.poses[p.b]);
    m.segment = seg;
    m.t_a_ns = recording.t_ns[p.a];
    m.t_b_ns = recording.t_ns[p.b];
    motions.push_back(m);
  }
  return motions;
}

}  // namespace rigcal
