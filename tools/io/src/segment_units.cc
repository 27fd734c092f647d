// SPDX-License-Identifier: Apache-2.0
// The unit of every odometry segment of a camera against its true trajectory.
#include <algorithm>
#include <map>

#include "rigcal/io/truth_comparison.h"

namespace rigcal::io {

std::vector<SegmentUnit> FitSegmentUnits(const std::vector<CameraPose>& poses,
                                         const TrueTrajectory& truth) {
  std::map<int, std::vector<std::pair<const CameraPose*, Pose>>> by_segment;
  for (const CameraPose& pose : poses) {
    if (std::optional<Pose> world_from_cam = truth(pose.t_ns)) {
      by_segment[pose.segment].emplace_back(&pose, *world_from_cam);
    }
  }
  std::vector<SegmentUnit> units;
  for (const auto& [segment, members] : by_segment) {
    // Positions relative to the segment's first pose, in its frame, on both sides: the
    // odometry's origin need not be its first pose written (an initialisation frame before it,
    // a pose dropped on the way), and a wrong origin shrinks the fitted unit.
    const Pose& true_first = members.front().second;
    const Pose& first = members.front().first->pose;
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
    for (const auto& [pose, world_from_cam] : members) {
      pairs.emplace_back(true_first.Between(world_from_cam).C, first.Between(pose->pose).C);
    }
    const UnitFit fit = FitUnit(pairs);
    SegmentUnit unit;
    unit.segment = segment;
    unit.poses = static_cast<int>(members.size());
    unit.metres_per_unit = members.size() >= 2 ? fit.metres_per_unit : 0.0;
    unit.fit_rms_m = fit.fit_rms_m;
    units.push_back(unit);
  }
  return units;
}

TrueTrajectory SampledTrajectory(TimedTrajectory samples) {
  std::vector<int64_t> intervals;
  for (size_t k = 1; k < samples.t_ns.size(); ++k) {
    intervals.push_back(samples.t_ns[k] - samples.t_ns[k - 1]);
  }
  int64_t max_gap_ns = 0;
  if (!intervals.empty()) {
    std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
    max_gap_ns = 3 * intervals[intervals.size() / 2];
  }
  return [samples = std::move(samples), max_gap_ns](int64_t t_ns) -> std::optional<Pose> {
    const std::vector<int64_t>& t = samples.t_ns;
    const auto after = std::lower_bound(t.begin(), t.end(), t_ns);
    if (after == t.end()) return std::nullopt;
    const size_t b = static_cast<size_t>(after - t.begin());
    if (t[b] == t_ns) return samples.poses[b];
    if (b == 0 || t[b] - t[b - 1] > max_gap_ns) return std::nullopt;
    const double w = static_cast<double>(t_ns - t[b - 1]) / static_cast<double>(t[b] - t[b - 1]);
    Pose pose = samples.poses[w < 0.5 ? b - 1 : b];
    pose.C = (1.0 - w) * samples.poses[b - 1].C + w * samples.poses[b].C;
    return pose;
  };
}

}  // namespace rigcal::io
