// SPDX-License-Identifier: Apache-2.0
#pragma once
// Machine-readable (JSON) and human-readable (text table) views of a calibration result.

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/base/types.h"
#include "rigcal/io/truth_alignment.h"

namespace rigcal::io {

// The result as JSON. Schema (shared by every command that prints results):
//   {"master": name,
//    "slaves": [{"name": s,
//                "q_wxyz": [w, x, y, z],      orientation of the slave in the master frame
//                "roll_pitch_yaw_deg": [r, p, y],   RollPitchYawDeg (not unique at pitch ±90)
//                "axis_angle": {"axis": [x, y, z], "angle_deg": a},  AxisAngleDeg (continuous
//                                             through pitch ±90)
//                "C": [x, y, z],              slave centre in the master frame, master units
//                "scale": s,                  when the slave has one scale, or else
//                "scales": [{"segment": id, "scale": s, "std": sigma}, ...],
//                "std": {"rot_deg": sigma, "pos": [sx, sy, sz],
//                        "axis": sigma,       σ of C along observability.mean_axis (null when
//                                             unknown: planar motion without a prior σ)
//                        "scale": sigma},     the one scale's σ (absent with "scales")
//                                             every σ null when unknown: the covariance was
//                                             not computed or failed (never 0)
//                "motions_used": n, "motions_rejected": n,
//                "glitches": {"dropped": n, "position_jump": n, "rotation_jump": n,
//                             "angle_mismatch": n, "in_master": n, "in_slave": n},
//                                             poses dropped before the pairs (GlitchCounts)
//                "models": {"motion": "general"|"planar"|"translational",
//                           "scale": "fixed"|"segments"|"partitions"},
//                "termination": ToString(Termination), "message": text,
//                "unobservable": [[x, y, z], ...],   unit directions, master frame; C along
//                                                    them is 0 (unknown) or the prior's
//                "unobservable_from_prior": bool,    C along them is the nominal mounting's
//                "observability": {"rotation_eigenvalues": [4, ascending],
//                                  "rotation_weak_std_deg", "position_min_eigenvalue",
//                                  "axis_spread_deg", "slave_axis_spread_deg", "tilt_snr",
//                                  "axis_std_ratio", "max_rotation_deg",
//                                  "planar": bool, "mean_axis": [x, y, z]},
//                "errors": {"rot_deg", "dir_deg", "dist_pct", "trans_err", "scale_pct",
//                           "plane_err", "axis_err"[, "trans_err_m"]}}],
//    "truth_alignment": {"mode": "auto"|"metric"|"master", "applied": bool,
//                        "metres_per_master_unit": k, "std": sigma, "fit_rms_m": r,
//                        "slaves_used": [names], "slave_excluded": name or null,
//                        "message": text}}    only when `alignment` is given
// Scale: slave odometry unit -> master unit. "errors" (CompareToTruth of error_model.h) is
// present only when `truth` (nullable) has an entry for the slave and the slave is usable;
// plane_err / axis_err split |C - C_true| at the mean rotation axis (null without one).
// rot_deg is the geodesic angle of q_true^-1 q_hat. `alignment` (nullable): how `truth` was
// brought into master units (TruthInMasterUnits: pass the converted truth); when applied,
// trans_err_m is trans_err in metres. Non-finite numbers become null.
nlohmann::json ResultToJson(const RigCalibration& result,
                            const std::map<std::string, Similarity>* truth,
                            const TruthAlignment* alignment = nullptr);

// Roll, pitch, yaw in degrees of the rotation R = Rz(yaw) Ry(pitch) Rx(roll) (ZYX Euler
// angles, as in ROS/Kalibr tooling); pitch in [-90, 90].
// At pitch ±90 (gimbal lock) only yaw - roll (or yaw + roll) is defined: roll is then 0.
Eigen::Vector3d RollPitchYawDeg(const Eigen::Quaterniond& q);

// The rotation as a unit axis and an angle in degrees in [0, 180] (the representative with
// w >= 0; the axis is (0, 0, 1) for the identity). Continuous wherever the angle is below
// 180, in particular through pitch ±90 where roll and yaw jump; at 180 the axis and its
// opposite are the same rotation and either may be reported.
struct AxisAngleDegrees {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  double angle_deg = 0.0;
};
AxisAngleDegrees AxisAngleDeg(const Eigen::Quaterniond& q);

// A text table of the result for terminals: per slave q (w, x, y, z), roll/pitch/yaw and
// axis/angle in degrees, C, scale(s), standard deviations, motions used/rejected, models,
// termination and message; with `truth` (nullable) the true values next to the estimates and
// the error model; with `alignment` (nullable) a line saying how the truth's unit was aligned
// (pass the truth in master units, TruthInMasterUnits) and the C errors in metres too.
std::string FormatResultTable(const RigCalibration& result,
                              const std::map<std::string, Similarity>* truth,
                              const TruthAlignment* alignment = nullptr);

}  // namespace rigcal::io
