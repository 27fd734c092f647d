// SPDX-License-Identifier: Apache-2.0
#pragma once
// What `rigcal status` knows of a running calibrator: the newest RIGCAL_STATUS (rig_status_t)
// and RIGCAL_EXTRINSICS (rig_extrinsics_t) and how old they are, the rig's health decided from
// them (the exit code of `rigcal status --once`), and their views: a dashboard for a terminal,
// plain lines for a log, one JSON object for scripts.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "rigcal/lcm/message_validation.h"
#include "rigcal/rig_extrinsics_t.hpp"
#include "rigcal/rig_status_t.hpp"

namespace rigcal::monitor {

struct MonitorSnapshot {
  std::string source;  // the LCM URL listened on, for the header ("" = LCM's default)
  std::optional<rig_status_t> status;
  std::optional<rig_extrinsics_t> extrinsics;
  // Seconds since the newest message of each kind arrived (receiver's clock: the senders'
  // utime may come from another host), -1 when none yet.
  double status_age_s = -1.0;
  double extrinsics_age_s = -1.0;
  int64_t status_received = 0;  // messages accepted since the monitor started
  int64_t extrinsics_received = 0;
  lcm::DecodeStats decode;        // accepted and rejected messages (a rejected one is never shown)
  double listening_s = 0.0;  // seconds since the monitor started listening
};

// The health `rigcal status --once` reports as its exit code.
enum class Health : int {
  kConverged = 0,     // every slave converged (σ settled)
  kConverging = 1,    // data arrive, not every slave has converged yet (idle, initialising,
                      // degraded, usable)
  kDecalibrated = 2,  // a slave's camera moved: the decalibration alarm
  kNoData = 3,        // neither RIGCAL_STATUS nor RIGCAL_EXTRINSICS arrived
};

// RIGCAL_STATUS's estimator_state when a status arrived, else the state combined from the
// slaves of RIGCAL_EXTRINSICS (CombineStates), else kNoData.
Health HealthOf(const MonitorSnapshot& snapshot);
// "converged", "converging", "decalibrated", "no_data".
const char* ToString(Health health);

// camera_status_t::VO_*: "initialising", "tracking", "lost", "dead" ("?" otherwise).
const char* VoStateName(int8_t vo_state);
// rig_status_t::ESTIMATOR_* as the RigState name (slave_state.h), "?" when undefined.
std::string EstimatorStateName(int8_t estimator_state);
// slave_extrinsics_t::STATE_* as the SlaveState name, "?" when undefined.
std::string SlaveStateName(int8_t state);

// The snapshot for scripts:
//   {"source": url, "health": ToString(HealthOf), "exit_code": n, "listening_s": s,
//    "status": null | {"age_s", "estimator_state", "estimator_message",
//                      "cameras": [{"name", "fps", "frames_received",
//                                   "dropped": {"late", "duplicate", "out_of_order", "overflow",
//                                               "never_matched", "invalid"},
//                                   "vo_state", "vo_segment", "last_pose_age_ms" (null when
//                                   none), "clock": {"source": "none"|"given"|"estimating"|
//                                   "estimated", "offset_s", "std_s", "drift_ppm",
//                                   "drift_std_ppm", "jumps"}}],
//                      "sync": {"sets_emitted", "fill", "capacity"},
//                      "process": {"cpu_percent", "rss_bytes"}},
//    "extrinsics": null | {"age_s", "t_ns", "master", "distance_unit": "master_odometry"|"metre",
//                          "slaves": [{"name", "state", "q_wxyz", "roll_pitch_yaw_deg",
//                                      "axis_angle": {"axis", "angle_deg"}, "C", "scale",
//                                      "segment", "std": {"rot_deg", "pos", "scale", "axis"},
//                                      "motions_used", "motions_rejected", "facts": [..],
//                                      "message"}]},
//    "rejected_messages": n}
// Unknown σ (-1 on LCM) and unknown axis offsets are null; "facts" lists "translational-only",
// "planar", "axis-from-prior", "refined".
nlohmann::json SnapshotToJson(const MonitorSnapshot& snapshot);

// The dashboard as text lines (no terminal control codes): a header with the source and the
// age of the newest messages, the rig's state and message, the calibrator's CPU and RSS, a table
// of the cameras (fps, frames, drops by cause, VO state, segment of a slave, pose age), the
// clock of every free-running slave (offset, σ, drift, jumps), the sync buffer, and per slave the
// estimate (axis/angle, roll/pitch/yaw, C, scale), its σ ("unknown" when unknown), motions
// used/rejected, state and facts. `width` caps the line length (0 = none).
std::string FormatDashboard(const MonitorSnapshot& snapshot, int width = 0);

// `text` as one refresh of a terminal screen: cursor home, every line followed by "clear to the
// end of the line", then "clear to the end of the screen" (ANSI/VT100, works over SSH).
std::string AnsiFrame(const std::string& text);

}  // namespace rigcal::monitor
