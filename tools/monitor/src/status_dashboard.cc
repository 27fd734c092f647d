// SPDX-License-Identifier: Apache-2.0
// The text views of a MonitorSnapshot: the dashboard and its ANSI frame.
#include <spdlog/fmt/fmt.h>

#include <limits>
#include <sstream>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/io/result_json.h"
#include "rigcal/lcm/slave_view.h"
#include "rigcal/monitor/status_snapshot.h"

namespace rigcal::monitor {
namespace {

// -1 (unknown on LCM) as NaN, which SigmaText prints as "unknown".
double Known(double sigma) {
  return sigma >= 0.0 ? sigma : std::numeric_limits<double>::quiet_NaN();
}

std::string AgeText(double age_s) {
  if (age_s < 0.0) return "never";
  return FixedText(age_s, 1) + " s ago";
}

std::string Bytes(int64_t bytes) {
  if (bytes >= (int64_t{1} << 30)) return FixedText(bytes / double(int64_t{1} << 30), 2) + " GiB";
  return FixedText(bytes / double(1 << 20), 1) + " MiB";
}

std::string JumpsText(int32_t jumps) {
  if (jumps <= 0) return "";
  return ", " + std::to_string(jumps) + (jumps == 1 ? " jump" : " jumps");
}

// A free-running camera's clock from RIGCAL_STATUS: "offset 40.012 ms sigma 0.21 ms, drift
// 50.1 ppm sigma 0.3 ppm (estimated), 1 jump".
std::string CameraClockText(const camera_status_t& c) {
  std::string text;
  switch (c.time_offset_source) {
    case slave_extrinsics_t::TIME_OFFSET_ESTIMATING:
      text = "offset being estimated";
      break;
    case slave_extrinsics_t::TIME_OFFSET_GIVEN:
      text = "offset " + FixedText(c.time_offset_s * 1e3, 3) + " ms (given)";
      break;
    case slave_extrinsics_t::TIME_OFFSET_NONE:  // the master: its restarts followed
      text = "the reference";
      break;
    default:
      text = "offset " + FixedText(c.time_offset_s * 1e3, 3) + " ms sigma " +
             SigmaText(Known(c.time_offset_std_s) * 1e3, 2) + " ms, drift " +
             FixedText(c.clock_drift_ppm, 1) + " ppm sigma " +
             SigmaText(Known(c.clock_drift_std_ppm), 2) + " ppm (estimated)";
  }
  return text + JumpsText(c.clock_jumps);
}

void AppendCameras(const MonitorSnapshot& snapshot, std::vector<std::string>* lines) {
  const rig_status_t& st = *snapshot.status;
  lines->push_back(
      fmt::format("{:<12} {:>6} {:>8} {:>6} {:>5} {:>5} {:>6} {:>8} {:>7}  {:<12} "
                  "{:>4} {:>5} {:>9}",
                  "camera", "fps", "frames", "late", "dup", "order", "ovfl", "unmatch", "invalid",
                  "VO", "seg", "reloc", "pose age"));
  for (const camera_status_t& c : st.cameras) {
    const std::string segment = c.vo_segment >= 0 ? std::to_string(c.vo_segment) : "-";
    const std::string age =
        c.last_pose_age_ms >= 0 ? std::to_string(c.last_pose_age_ms) + " ms" : "none";
    lines->push_back(fmt::format(
        "{:<12} {:>6} {:>8} {:>6} {:>5} {:>5} {:>6} {:>8} {:>7}  {:<12} {:>4} {:>5} {:>9}", c.name,
        FixedText(c.fps, 1), c.frames_received, c.dropped_late, c.dropped_duplicate,
        c.dropped_out_of_order, c.dropped_overflow, c.dropped_never_matched, c.dropped_invalid,
        VoStateName(c.vo_state), segment, c.relocalisations, age));
  }
  for (const camera_status_t& c : st.cameras) {
    if (c.time_offset_source != slave_extrinsics_t::TIME_OFFSET_NONE || c.clock_jumps > 0) {
      lines->push_back(fmt::format("clock {:<12} {}", c.name, CameraClockText(c)));
    }
  }
  lines->push_back(fmt::format("sync: {} sets emitted, buffer {} / {}", st.sync_sets_emitted,
                               st.sync_fill, st.sync_capacity));
}

// A free-running slave's clock offset: "offset 40.012 ms sigma 0.21 ms (estimated), 1 jump".
std::string ClockOffsetText(const slave_extrinsics_t& s) {
  std::string text;
  switch (s.time_offset_source) {
    case slave_extrinsics_t::TIME_OFFSET_ESTIMATING:
      text = "offset being estimated (the slave waits for it)";
      break;
    case slave_extrinsics_t::TIME_OFFSET_GIVEN:
      text = "offset " + FixedText(s.time_offset_s * 1e3, 3) + " ms (given)";
      break;
    default:
      text = "offset " + FixedText(s.time_offset_s * 1e3, 3) + " ms  sigma " +
             SigmaText(Known(s.time_offset_std_s) * 1e3, 2) + " ms (estimated)";
  }
  if (s.clock_jumps > 0) {
    text += ", " + std::to_string(s.clock_jumps) + (s.clock_jumps == 1 ? " jump" : " jumps");
  }
  return text;
}

void AppendSlaves(const rig_extrinsics_t& ex, std::vector<std::string>* lines) {
  const char* unit = ex.distance_unit == rig_extrinsics_t::UNIT_METRE ? "m" : "master units";
  for (const slave_extrinsics_t& s : ex.slaves) {
    const lcm::SlaveView view = lcm::ViewOf(s);
    std::string state = SlaveStateName(s.state);
    for (const std::string& fact : view.facts) state += " " + fact;
    lines->push_back(fmt::format("slave {} (master {}): {}  motions {} used, {} rejected", s.name,
                                 ex.master, state, s.motions_used, s.motions_rejected));
    const io::AxisAngleDegrees a = io::AxisAngleDeg(view.q);
    lines->push_back(fmt::format("  rotation  axis {} angle {} deg  rpy {} deg  sigma {} deg",
                                 VectorText(a.axis, 4), FixedText(a.angle_deg, 3),
                                 VectorText(io::RollPitchYawDeg(view.q), 3),
                                 SigmaText(Known(s.rot_std_deg), 3)));
    lines->push_back(fmt::format(
        "  position  C {} {}  sigma {}  scale {} sigma {}  segment {}",
        VectorText(Eigen::Vector3d(s.C[0], s.C[1], s.C[2]), 4), unit,
        SigmaVectorText(
            Eigen::Vector3d(Known(s.pos_std[0]), Known(s.pos_std[1]), Known(s.pos_std[2])), 3),
        SignificantText(s.scale, 6), SigmaText(Known(s.scale_std), 3), s.segment));
    if (s.time_offset_source != slave_extrinsics_t::TIME_OFFSET_NONE) {
      lines->push_back("  clock     " + ClockOffsetText(s));
    }
    if (!s.message.empty()) lines->push_back("  " + s.message);
  }
}

}  // namespace

std::string FormatDashboard(const MonitorSnapshot& snapshot, int width) {
  std::vector<std::string> lines;
  const std::string source = snapshot.source.empty() ? "LCM default URL" : snapshot.source;
  lines.push_back(
      fmt::format("rigcal status  {}  listening {} s", source, FixedText(snapshot.listening_s, 0)));
  lines.push_back(fmt::format(
      "RIGCAL_STATUS {} ({} received)   RIGCAL_EXTRINSICS {} ({} received)"
      "   rejected {}",
      AgeText(snapshot.status_age_s), snapshot.status_received, AgeText(snapshot.extrinsics_age_s),
      snapshot.extrinsics_received, snapshot.decode.TotalRejected()));
  const Health health = HealthOf(snapshot);
  if (health == Health::kNoData) {
    lines.push_back("waiting for RIGCAL_STATUS and RIGCAL_EXTRINSICS ...");
  } else {
    lines.push_back(
        fmt::format("health: {} (exit code {})", ToString(health), static_cast<int>(health)));
  }
  if (snapshot.status) {
    const rig_status_t& st = *snapshot.status;
    lines.push_back(fmt::format("rig: {}{}{}", EstimatorStateName(st.estimator_state),
                                st.estimator_message.empty() ? "" : " - ", st.estimator_message));
    lines.push_back(fmt::format("calibrator: CPU {} %  RSS {}", FixedText(st.cpu_percent, 1),
                                Bytes(st.rss_bytes)));
    lines.emplace_back();
    AppendCameras(snapshot, &lines);
  }
  if (snapshot.extrinsics) {
    lines.emplace_back();
    AppendSlaves(*snapshot.extrinsics, &lines);
  }
  std::string out;
  for (std::string& line : lines) {
    if (width > 0 && static_cast<int>(line.size()) > width) line.resize(width);
    out += line + "\n";
  }
  return out;
}

std::string AnsiFrame(const std::string& text) {
  std::string out = "\x1b[H";
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) out += line + "\x1b[K\n";
  return out + "\x1b[J";
}

}  // namespace rigcal::monitor
