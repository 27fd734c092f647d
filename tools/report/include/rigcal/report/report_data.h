// SPDX-License-Identifier: Apache-2.0
#pragma once
// What `rigcal report` shows, gathered from its inputs (report_input.h) before it is drawn
// (report_html.h): the estimate's history from RIGCAL_EXTRINSICS, the cameras' health from
// RIGCAL_STATUS, the per-motion residua and measured scales from the poses, the final result
// and the truth.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/slave_state.h"
#include "rigcal/camera/camera_spec.h"

namespace rigcal::report {

inline constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();

// One slave in one RIGCAL_EXTRINSICS message. σ NaN = unknown.
struct EstimateSample {
  double t_s = 0.0;  // seconds since ReportData::t0_ns
  Similarity estimate;
  double rot_std_deg = kUnknown;
  Eigen::Vector3d pos_std = Eigen::Vector3d::Constant(kUnknown);
  double scale_std = kUnknown;
  int motions_used = 0;
  SlaveState state = SlaveState::kInitialising;
};

// One camera in one RIGCAL_STATUS message.
struct CameraHealthSample {
  double t_s = 0.0;  // seconds since the first RIGCAL_STATUS
  double fps = 0.0;
  int64_t frames_received = 0;
  int64_t dropped = 0;  // every cause, cumulative
  int8_t vo_state = 0;  // camera_status_t::VO_*
  int64_t last_pose_age_ms = -1;
  int32_t relocalisations = 0;  // cumulative (rig_status_t version 5)
  // The camera's clock (rig_status_t version 4): its offset to the master clock when given or
  // estimated (kUnknown otherwise: the master, synchronised stamps, still being estimated), and
  // the restarts of it detected so far.
  double time_offset_ms = kUnknown;
  int32_t clock_jumps = 0;
};

// One motion of one slave (thesis fig. 5.11 and 5.12), against the final estimate.
struct MotionSample {
  double t_s = 0.0;                   // mid-time of the motion, seconds since ReportData::t0_ns
  double rotation_deg = 0.0;          // rotation constraint residuum
  double position_dir_deg = 0.0;      // position constraint residuum as an angle
  double position_abs = 0.0;          // |(R_0 - I) dC + C_0 - s dR C_i|, master units
  double master_axis_dot = kUnknown;  // C_0^T r_0 of (4.18)
  double slave_axis_dot = kUnknown;   // C_i^T r_i
  double measured_scale = kUnknown;   // λ^k = C_0^T r_0 / C_i^T r_i
  bool scale_used = false;            // |C_i^T r_i| > the threshold (4.23)
};

struct SlaveMotions {
  std::vector<MotionSample> samples;
  double scale_threshold = 0.0;  // δ = 3 ε of (4.23) on |C_i^T r_i|
  double reference_scale = 1.0;  // the final estimate's scale (its latest segment)
};

struct MotionAnalysis {
  std::string source;  // the pose log the motions come from
  std::string pairs;   // which pairs of times became motions ("walk", PairsText)
  std::map<std::string, SlaveMotions> slaves;
};

struct ReportData {
  std::string input;      // the file the report is about
  bool from_log = false;  // an LCM log (history) rather than a result file
  std::string master;
  std::vector<std::string> slaves;  // table and plot order
  std::string distance_unit = "master units";
  // Metres per unit of the final table's C: 1 when C is in metres (a metric master, a target
  // reference, --metric-*: the log's or result's unit, or the config's metric master), the
  // master unit fitted to a metric truth, NaN when unknown; `metres_source` says which.
  double metres_per_unit = kUnknown;
  std::string metres_source;
  // The rig config's cameras with intrinsics (rig order), empty without --config.
  std::vector<camera::CameraSpec> intrinsics;
  std::string config;  // the rig config's path
  int64_t t0_ns = 0;   // time origin of the estimate history and the motions

  // RIGCAL_EXTRINSICS history (empty for a result file).
  std::map<std::string, std::vector<EstimateSample>> estimates;
  int64_t extrinsics_messages = 0;
  // RIGCAL_STATUS history, per camera (empty for a result file).
  std::vector<std::string> cameras;
  std::map<std::string, std::vector<CameraHealthSample>> health;
  int64_t status_messages = 0;
  // Some camera runs free (a clock offset in RIGCAL_STATUS): the health figure shows the clocks.
  bool free_running = false;

  // The final table: the result file, or the last RIGCAL_EXTRINSICS.
  RigCalibration final_result;
  // Truth per slave in the estimate's unit (TruthInMasterUnits), empty when not known.
  std::map<std::string, Similarity> truth;
  std::optional<MotionAnalysis> motions;
  // What is missing and why, how the truth was aligned, problems of the inputs: one sentence
  // each, shown at the top of the report.
  std::vector<std::string> notes;
  // Where the report came from, one line each (which rigcal and when, the command line, every
  // input with its size and hash); filled by the command, shown under the title.
  std::vector<std::string> provenance;
};

}  // namespace rigcal::report
