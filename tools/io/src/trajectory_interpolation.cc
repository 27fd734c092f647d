// SPDX-License-Identifier: Apache-2.0
// Interpolation of a trajectory at other instants (cameras that run free).
#include "rigcal/io/trajectory_interpolation.h"

#include <algorithm>
#include <cmath>

namespace rigcal::io {

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

}  // namespace rigcal::io
