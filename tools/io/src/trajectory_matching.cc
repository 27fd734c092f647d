// SPDX-License-Identifier: Apache-2.0
// MatchTrajectories: the poses of several cameras matched by time stamp into a RigRecording.
#include <algorithm>
#include <array>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/io/trajectory_io.h"
#include "trajectory_text.h"

namespace rigcal::io {
namespace {

std::string FormatRange(const TimedTrajectory& t) {
  std::array<char, 96> buf{};
  std::snprintf(buf.data(), buf.size(), "%.3f..%.3f s", static_cast<double>(t.t_ns.front()) * 1e-9,
                static_cast<double>(t.t_ns.back()) * 1e-9);
  return t.name + " " + buf.data();
}

// Index of the stamp in sorted `stamps` nearest to `t` (the earlier one on a tie).
size_t Nearest(const std::vector<int64_t>& stamps, int64_t t) {
  const auto it = std::lower_bound(stamps.begin(), stamps.end(), t);
  if (it == stamps.begin()) return 0;
  if (it == stamps.end()) return stamps.size() - 1;
  const size_t hi = static_cast<size_t>(it - stamps.begin());
  // Compare distances without overflow: both differences are non-negative.
  const uint64_t d_hi = static_cast<uint64_t>(*it) - static_cast<uint64_t>(t);
  const uint64_t d_lo = static_cast<uint64_t>(t) - static_cast<uint64_t>(*(it - 1));
  return d_lo <= d_hi ? hi - 1 : hi;
}

uint64_t AbsDiff(int64_t a, int64_t b) {
  return a >= b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
}

std::string CheckTrajectory(const TimedTrajectory& t) {
  if (t.t_ns.empty()) return "camera '" + t.name + "' has no poses";
  if (t.poses.size() != t.t_ns.size() ||
      (!t.segment.empty() && t.segment.size() != t.t_ns.size())) {
    return "camera '" + t.name + "': t_ns, poses and segment differ in size";
  }
  if (!std::is_sorted(t.t_ns.begin(), t.t_ns.end())) {
    return "camera '" + t.name + "': stamps are not sorted";
  }
  return "";
}

CameraTrack TrackOf(const TimedTrajectory& t, const std::vector<size_t>& indices) {
  CameraTrack track;
  track.name = t.name;
  track.poses.reserve(indices.size());
  track.segment.reserve(indices.size());
  for (const size_t i : indices) {
    track.poses.push_back(t.poses[i]);
    track.segment.push_back(t.segment.empty() ? 0 : t.segment[i]);
  }
  return track;
}

}  // namespace

Expected<RigRecording> MatchTrajectories(const TimedTrajectory& master,
                                         const std::vector<TimedTrajectory>& slaves,
                                         int64_t tolerance_ns) {
  if (tolerance_ns < 0) return Error{"the matching tolerance must not be negative"};
  if (slaves.empty()) return Error{"no slave trajectories to match"};
  std::vector<const TimedTrajectory*> all = {&master};
  for (const auto& s : slaves) all.push_back(&s);
  for (size_t i = 0; i < all.size(); ++i) {
    if (const std::string problem = CheckTrajectory(*all[i]); !problem.empty()) {
      return Error{problem};
    }
    for (size_t j = 0; j < i; ++j) {
      if (all[i]->name == all[j]->name) {
        return Error{"two cameras are named '" + all[i]->name +
                     "' (camera names are file stems, or NAME of a NAME=FILE argument, and must "
                     "differ)"};
      }
    }
  }

  // Common time range, widened by the tolerance.
  int64_t lo = master.t_ns.front();
  int64_t hi = master.t_ns.back();
  for (const auto& s : slaves) {
    lo = std::max(lo, s.t_ns.front());
    hi = std::min(hi, s.t_ns.back());
  }
  if (lo > hi && AbsDiff(lo, hi) > static_cast<uint64_t>(tolerance_ns)) {
    std::string message = "no overlapping time range: master " + FormatRange(master);
    for (const auto& s : slaves) message += ", " + FormatRange(s);
    return Error{message};
  }

  // matched[s][k]: index into slave s matched to master stamp k, or npos.
  constexpr size_t kNone = std::numeric_limits<size_t>::max();
  std::vector<std::vector<size_t>> matched(slaves.size(),
                                           std::vector<size_t>(master.size(), kNone));
  std::vector<int> count(slaves.size(), 0);
  for (size_t s = 0; s < slaves.size(); ++s) {
    const auto& slave_t = slaves[s].t_ns;
    for (size_t k = 0; k < master.size(); ++k) {
      const size_t j = Nearest(slave_t, master.t_ns[k]);
      if (AbsDiff(slave_t[j], master.t_ns[k]) > static_cast<uint64_t>(tolerance_ns)) continue;
      if (Nearest(master.t_ns, slave_t[j]) != k) continue;
      matched[s][k] = j;
      ++count[s];
    }
  }

  std::vector<size_t> master_indices;
  std::vector<std::vector<size_t>> slave_indices(slaves.size());
  for (size_t k = 0; k < master.size(); ++k) {
    const bool in_all = std::all_of(matched.begin(), matched.end(),
                                    [k](const std::vector<size_t>& m) { return m[k] != kNone; });
    if (!in_all) continue;
    master_indices.push_back(k);
    for (size_t s = 0; s < slaves.size(); ++s) slave_indices[s].push_back(matched[s][k]);
  }
  if (master_indices.size() < 2) {
    std::string message = "only " + std::to_string(master_indices.size()) +
                          " master stamps have a pose in every slave within " +
                          SignificantText(static_cast<double>(tolerance_ns) * 1e-6, 9) +
                          " ms (need at least 2); per slave:";
    for (size_t s = 0; s < slaves.size(); ++s) {
      message += (s ? ", " : " ") + slaves[s].name + " matched " + std::to_string(count[s]) +
                 " of " + std::to_string(master.size());
    }
    return Error{message};
  }

  RigRecording recording;
  recording.t_ns.reserve(master_indices.size());
  for (const size_t k : master_indices) recording.t_ns.push_back(master.t_ns[k]);
  recording.master = TrackOf(master, master_indices);
  for (size_t s = 0; s < slaves.size(); ++s) {
    recording.slaves.push_back(TrackOf(slaves[s], slave_indices[s]));
  }
  return recording;
}

}  // namespace rigcal::io
