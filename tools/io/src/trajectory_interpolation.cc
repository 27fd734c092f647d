// Interpolation of a trajectory at other instants (cameras that run free).
#include "rigcal/io/trajectory_interpolation.h"

#include <algorithm>
#include <cmath>

namespace rigcal::tools {

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
  const Pose& a = trajectory.poses[lo];
  const bool cubic = lo > 0 && hi + 1 < t.size() && t[lo] - t[lo - 1] <= max_gap_ns &&
                     t[hi + 1] - t[hi] <= max_gap_ns && segment_of(lo - 1) == out.segment &&
                     segment_of(hi + 1) == out.segment;
  if (!cubic) {
    const double f = static_cast<double>(t_ns - t[lo]) / static_cast<double>(t[hi] - t[lo]);
    const Pose& b = trajectory.poses[hi];
    out.pose.q = a.q.slerp(f, b.q).normalized();
    out.pose.C = (1.0 - f) * a.C + f * b.C;
    return out;
  }
  // Cubic Lagrange through the poses lo - 1 .. hi + 1: the centre directly, the rotation as
  // rotation vectors in the tangent space of pose lo.
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  for (size_t i = lo - 1; i <= hi + 1; ++i) {
    double w = 1.0;
    for (size_t m = lo - 1; m <= hi + 1; ++m) {
      if (m == i) continue;
      w *= static_cast<double>(t_ns - t[m]) / static_cast<double>(t[i] - t[m]);
    }
    const Pose& p = trajectory.poses[i];
    c += w * p.C;
    const Eigen::AngleAxisd rel(a.q.conjugate() * p.q);
    v += w * rel.angle() * rel.axis();
  }
  out.pose.C = c;
  out.pose.q =
      v.norm() > 0.0
          ? (a.q * Eigen::Quaterniond(Eigen::AngleAxisd(v.norm(), v.normalized()))).normalized()
          : a.q;
  return out;
}

TimedTrajectory ResampleAt(const TimedTrajectory& slave, const std::vector<int64_t>& master_t_ns,
                           int64_t offset_ns, const InterpolationOptions& options) {
  const auto max_gap_ns = static_cast<int64_t>(
      std::llround(options.max_gap_intervals * static_cast<double>(MedianInterval(slave.t_ns))));
  TimedTrajectory out;
  out.name = slave.name;
  for (const int64_t t : master_t_ns) {
    const auto p = InterpolatePose(slave, t + offset_ns, max_gap_ns);
    if (!p) continue;
    out.t_ns.push_back(t);
    out.poses.push_back(p->pose);
    out.segment.push_back(p->segment);
  }
  return out;
}

TimedTrajectory ShiftedToMasterClock(const TimedTrajectory& slave, int64_t offset_ns) {
  TimedTrajectory out = slave;
  for (int64_t& t : out.t_ns) t -= offset_ns;
  return out;
}

bool StampsCoincide(const TimedTrajectory& master, const TimedTrajectory& slave, int64_t offset_ns,
                    int64_t tolerance_ns) {
  if (master.size() < 2 || slave.size() < 2) return false;
  const int64_t threshold = std::min(tolerance_ns, MedianInterval(master.t_ns) / 50);
  size_t inside = 0;
  size_t close = 0;
  for (const int64_t t : master.t_ns) {
    const int64_t ts = t + offset_ns;
    if (ts < slave.t_ns.front() || ts > slave.t_ns.back()) continue;
    ++inside;
    const auto it = std::lower_bound(slave.t_ns.begin(), slave.t_ns.end(), ts);
    int64_t d = *it - ts;
    if (it != slave.t_ns.begin()) d = std::min(d, ts - *(it - 1));
    if (d <= threshold) ++close;
  }
  return inside > 0 && static_cast<double>(close) >= 0.9 * static_cast<double>(inside);
}

Expected<RigRecording> MatchFreeRunning(const TimedTrajectory& master,
                                        const std::vector<TimedTrajectory>& slaves,
                                        const std::vector<int64_t>& offsets_ns,
                                        int64_t tolerance_ns, const InterpolationOptions& options,
                                        std::vector<bool>* interpolated) {
  if (offsets_ns.size() != slaves.size()) {
    return Error{"one time offset per slave expected, got " + std::to_string(offsets_ns.size()) +
                 " for " + std::to_string(slaves.size()) + " slaves"};
  }
  std::vector<TimedTrajectory> matched;
  if (interpolated) interpolated->clear();
  for (size_t i = 0; i < slaves.size(); ++i) {
    TimedTrajectory resampled;
    if (!StampsCoincide(master, slaves[i], offsets_ns[i], tolerance_ns)) {
      resampled = ResampleAt(slaves[i], master.t_ns, offsets_ns[i], options);
    }
    // Nothing to interpolate (no common time): MatchTrajectories says why.
    const bool by_stamp = resampled.size() == 0;
    matched.push_back(by_stamp ? ShiftedToMasterClock(slaves[i], offsets_ns[i]) : resampled);
    if (interpolated) interpolated->push_back(!by_stamp);
  }
  return MatchTrajectories(master, matched, tolerance_ns);
}

}  // namespace rigcal::tools
