// SPDX-License-Identifier: Apache-2.0
// Gross pose outliers found from each camera's own trajectory (pose_glitches.h).
#include "motions/pose_glitches.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <utility>

#include "motions/non_finite.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {
namespace {

double StepSeconds(const RigRecording& rec, int a, int b) {
  return std::max(1e-9 * static_cast<double>(rec.t_ns[b] - rec.t_ns[a]), 1e-12);
}

// Maximal index ranges [first, last) over which `same(k - 1, k)` holds for every step.
std::vector<std::pair<int, int>> Runs(int n, const std::function<bool(int, int)>& same) {
  std::vector<std::pair<int, int>> runs;
  int first = 0;
  for (int k = 1; k <= n; ++k) {
    if (k == n || !same(k - 1, k)) {
      runs.emplace_back(first, k);
      first = k;
    }
  }
  return runs;
}

// The values of steps j - window .. j + window inside the segment (steps first + 1 .. last - 1).
std::vector<double> LocalWindow(const std::vector<double>& values, int j, int first, int last,
                                int window) {
  std::vector<double> w;
  for (int i = std::max(first + 1, j - window); i <= std::min(last - 1, j + window); ++i) {
    if (std::isfinite(values[i])) w.push_back(values[i]);
  }
  return w;
}

// One consistency test on one segment [first, last): step j (pose j - 1 -> j) has the value
// value[j] and the threshold limit[j]; bridged(a, b) is the value of the step a -> b over the
// poses between. Marks the glitched poses (see pose_glitches.h for the runs).
void MarkRuns(int first, int last, const std::vector<double>& value,
              const std::vector<double>& limit, const GlitchTest& test,
              const std::function<double(int, int)>& bridged, std::vector<bool>* glitched) {
  auto outlier = [&](int j) { return value[j] > limit[j]; };
  int j = first + 1;
  while (j < last) {
    if (!outlier(j)) {
      ++j;
      continue;
    }
    const int a = j - 1;
    int exit = -1;  // b: the first pose after the run
    for (int b = a + 2; b < last && b - a - 1 <= test.max_run; ++b) {
      // Real motion bridges at about the mean of its steps (a turn that ends: 0.55, 0.46, 0.26
      // rad/s bridge at 0.42); a glitch leaves the typical value, far below both jumps.
      const double bridge = bridged(a, b);
      if (outlier(b) && !(bridge > std::max(limit[j], limit[b])) &&
          !(test.jump_factor * bridge > std::min(value[j], value[b]))) {
        exit = b;
        break;
      }
    }
    if (exit > 0) {
      for (int k = a + 1; k < exit; ++k) (*glitched)[k] = true;
      j = exit + 1;
      continue;
    }
    // No bridge: a run at the start of the segment (the step after it normal and below the
    // jump by jump_factor), or at its end (the step before it so).
    auto below = [&](int i) {
      return i <= first || i >= last || (!outlier(i) && test.jump_factor * value[i] <= value[j]);
    };
    if (a - first + 1 <= test.max_run && below(j + 1)) {
      for (int k = first; k <= a; ++k) (*glitched)[k] = true;
    } else if (last - 1 - a <= test.max_run && below(j - 1)) {
      bool tail = true;  // every step of the tail runs away from the segment's motion
      for (int k = a + 1; k < last; ++k) tail = tail && bridged(a, k) > limit[j];
      if (tail) {
        for (int k = a + 1; k < last; ++k) (*glitched)[k] = true;
        break;
      }
    }
    ++j;
  }
}

// Thresholds of a speed per step: against the local and the camera's overall median.
std::vector<double> SpeedLimits(const std::vector<double>& speed, int first, int last,
                                double overall_median, double floor, const GlitchTest& test) {
  std::vector<double> limit(speed.size(), kNaN);
  for (int j = first + 1; j < last; ++j) {
    const RobustStats local = MedianAndSigma(LocalWindow(speed, j, first, last, test.window));
    limit[j] = OutlierSpeed(test, std::max(local.median, overall_median), local.median, local.sigma,
                            floor);
  }
  return limit;
}

// Position and rotation jumps of one camera's track.
void FindJumps(const RigRecording& rec, const CameraTrack& track, const GlitchTest& test,
               std::vector<bool>* position, std::vector<bool>* rotation) {
  const int n = static_cast<int>(rec.size());
  std::vector<double> speed(n, kNaN), turn(n, kNaN);
  double largest = 0.0;
  for (int k = 0; k < n; ++k) largest = std::max(largest, track.poses[k].C.norm());
  std::vector<double> dts;
  const auto runs = Runs(n, [&](int a, int b) { return track.SegmentAt(a) == track.SegmentAt(b); });
  for (const auto& [first, last] : runs) {
    for (int j = first + 1; j < last; ++j) {
      const double dt = StepSeconds(rec, j - 1, j);
      dts.push_back(dt);
      speed[j] = (track.poses[j].C - track.poses[j - 1].C).norm() / dt;
      turn[j] = AngleBetween(track.poses[j - 1].q, track.poses[j].q) / dt;
    }
  }
  std::vector<double> speeds, turns;
  for (int j = 0; j < n; ++j) {
    if (std::isfinite(speed[j])) speeds.push_back(speed[j]);
    if (std::isfinite(turn[j])) turns.push_back(turn[j]);
  }
  const double dt = Median(dts);
  const double overall_speed = Median(speeds), overall_turn = Median(turns);
  for (const auto& [first, last] : runs) {
    if (last - first - 1 < test.min_steps) continue;
    const std::vector<double> speed_limit = SpeedLimits(
        speed, first, last, overall_speed, kGlitchResolution * (1.0 + largest) / dt, test);
    MarkRuns(
        first, last, speed, speed_limit, test,
        [&](int a, int b) {
          return (track.poses[b].C - track.poses[a].C).norm() / StepSeconds(rec, a, b);
        },
        position);
    const std::vector<double> turn_limit =
        SpeedLimits(turn, first, last, overall_turn, kGlitchResolution / dt, test);
    MarkRuns(
        first, last, turn, turn_limit, test,
        [&](int a, int b) {
          return AngleBetween(track.poses[a].q, track.poses[b].q) / StepSeconds(rec, a, b);
        },
        rotation);
  }
}

// Master/slave rotation-angle mismatches of slave `slave`: marks the glitched poses of the
// master in `master`, of the slave in `slave_marks`.
void FindAngleMismatches(const RigRecording& rec, int slave, const GlitchTest& test,
                         std::vector<bool>* master, std::vector<bool>* slave_marks) {
  const CameraTrack& m = rec.master;
  const CameraTrack& s = rec.slaves[slave];
  const int n = static_cast<int>(rec.size());
  auto difference = [&](int a, int b) {
    return AngleBetween(m.poses[a].q, m.poses[b].q) - AngleBetween(s.poses[a].q, s.poses[b].q);
  };
  const auto runs = Runs(n, [&](int a, int b) {
    return m.SegmentAt(a) == m.SegmentAt(b) && s.SegmentAt(a) == s.SegmentAt(b);
  });
  std::vector<double> diff(n, kNaN), all;
  for (const auto& [first, last] : runs) {
    for (int j = first + 1; j < last; ++j) all.push_back(diff[j] = difference(j - 1, j));
  }
  const RobustStats overall = MedianAndSigma(all);
  std::vector<double> value(n, kNaN), limit(n, kNaN);
  for (int j = 0; j < n; ++j) {
    if (std::isfinite(diff[j])) value[j] = std::abs(diff[j] - overall.median);
  }
  for (const auto& [first, last] : runs) {
    if (last - first - 1 < test.min_steps) continue;
    for (int j = first + 1; j < last; ++j) {
      const RobustStats local = MedianAndSigma(LocalWindow(diff, j, first, last, test.window));
      limit[j] = test.outlier_sigmas * std::max(overall.sigma, local.sigma) + kGlitchResolution;
    }
    std::vector<bool> glitched(n, false);
    MarkRuns(
        first, last, value, limit, test,
        [&](int a, int b) { return std::abs(difference(a, b) - overall.median); }, &glitched);
    // Whose: the camera whose rotation through the run is the less direct.
    for (int k = first; k < last;) {
      if (!glitched[k]) {
        ++k;
        continue;
      }
      int end = k;
      while (end < last && glitched[end]) ++end;
      const int a = std::max(first, k - 1), b = std::min(last - 1, end);
      double excess_master = -AngleBetween(m.poses[a].q, m.poses[b].q);
      double excess_slave = -AngleBetween(s.poses[a].q, s.poses[b].q);
      for (int i = a + 1; i <= b; ++i) {
        excess_master += AngleBetween(m.poses[i - 1].q, m.poses[i].q);
        excess_slave += AngleBetween(s.poses[i - 1].q, s.poses[i].q);
      }
      std::vector<bool>* marks = excess_master > excess_slave ? master : slave_marks;
      for (int i = k; i < end; ++i) (*marks)[i] = true;
      k = end;
    }
  }
}

}  // namespace

double OutlierSpeed(const GlitchTest& test, double typical, double median, double sigma,
                    double floor) {
  return std::max({test.jump_factor * typical, median + test.outlier_sigmas * sigma, floor});
}

GlitchCounts GlitchReport::CountsFor(int slave) const {
  GlitchCounts c;
  // `glitches` is ordered by index: one pass over the entries of each dropped time.
  for (size_t i = 0; i < glitches.size();) {
    GlitchCause cause = GlitchCause::kAngleMismatch;
    bool master = false, in_slave = false;
    const int index = glitches[i].index;
    for (; i < glitches.size() && glitches[i].index == index; ++i) {
      cause = std::min(cause, glitches[i].cause);
      master = master || glitches[i].camera == 0;
      in_slave = in_slave || glitches[i].camera == slave + 1;
    }
    c.position_jump += cause == GlitchCause::kPositionJump;
    c.rotation_jump += cause == GlitchCause::kRotationJump;
    c.angle_mismatch += cause == GlitchCause::kAngleMismatch;
    c.in_master += master;
    c.in_slave += in_slave;
  }
  return c;
}

GlitchReport FindGlitches(const RigRecording& recording, const GlitchTest& test) {
  GlitchReport report;
  if (!recording.Check().ok()) return report;
  const int n = static_cast<int>(recording.size());
  const int cameras = 1 + static_cast<int>(recording.slaves.size());
  std::map<std::pair<int, int>, GlitchCause> found;  // (index, camera) -> first cause
  auto take = [&](int camera, const std::vector<bool>& marks, GlitchCause cause) {
    for (int k = 0; k < n; ++k) {
      if (!marks[k]) continue;
      auto [it, added] = found.emplace(std::make_pair(k, camera), cause);
      if (!added) it->second = std::min(it->second, cause);
    }
  };
  for (int c = 0; c < cameras; ++c) {
    const CameraTrack& track = c == 0 ? recording.master : recording.slaves[c - 1];
    std::vector<bool> position(n, false), rotation(n, false);
    FindJumps(recording, track, test, &position, &rotation);
    take(c, position, GlitchCause::kPositionJump);
    take(c, rotation, GlitchCause::kRotationJump);
  }
  for (int i = 0; i + 1 < cameras; ++i) {
    std::vector<bool> master(n, false), slave(n, false);
    FindAngleMismatches(recording, i, test, &master, &slave);
    take(0, master, GlitchCause::kAngleMismatch);
    take(i + 1, slave, GlitchCause::kAngleMismatch);
  }
  for (const auto& [key, cause] : found) {
    report.glitches.push_back({key.first, key.second, cause});
    if (report.dropped.empty() || report.dropped.back() != key.first) {
      report.dropped.push_back(key.first);
    }
  }
  return report;
}

RigRecording WithoutGlitches(const RigRecording& recording, GlitchReport* report) {
  GlitchReport found = FindGlitches(recording);
  RigRecording out;
  if (found.dropped.empty()) {
    out = recording;
  } else {
    out.master.name = recording.master.name;
    for (const CameraTrack& s : recording.slaves) out.slaves.push_back({s.name, {}, {}});
    auto keep = [](const CameraTrack& from, size_t k, CameraTrack* to) {
      to->poses.push_back(from.poses[k]);
      if (!from.segment.empty()) to->segment.push_back(from.segment[k]);
    };
    size_t next = 0;
    for (size_t k = 0; k < recording.size(); ++k) {
      if (next < found.dropped.size() && found.dropped[next] == static_cast<int>(k)) {
        ++next;
        continue;
      }
      out.t_ns.push_back(recording.t_ns[k]);
      keep(recording.master, k, &out.master);
      for (size_t i = 0; i < recording.slaves.size(); ++i) {
        keep(recording.slaves[i], k, &out.slaves[i]);
      }
    }
  }
  if (report != nullptr) *report = std::move(found);
  return out;
}

std::string GlitchText(const GlitchCounts& c, const std::string& noun, const std::string& verb) {
  if (c.dropped() == 0) return "";
  auto count = [](int n, const std::string& one, const std::string& many) {
    return std::to_string(n) + " " + (n == 1 ? one : many);
  };
  return count(c.dropped(), noun, noun + "s") + " " + verb + " as glitches (" +
         count(c.position_jump, "position jump", "position jumps") + ", " +
         count(c.rotation_jump, "rotation jump", "rotation jumps") + ", " +
         count(c.angle_mismatch, "angle mismatch", "angle mismatches") + "; " +
         std::to_string(c.in_master) + " in the master, " + std::to_string(c.in_slave) +
         " in this camera)";
}

void ReportGlitches(const GlitchReport& report, int slave, SlaveCalibration* result) {
  result->glitches = report.CountsFor(slave);
  const std::string text = GlitchText(result->glitches);
  if (!text.empty()) result->message += (result->message.empty() ? "" : "; ") + text;
}

}  // namespace rigcal::internal
