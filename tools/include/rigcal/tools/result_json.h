#pragma once
// Machine-readable (JSON) and human-readable (text table) views of a calibration result.

#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/types.h"

namespace rigcal::tools {

// The result as JSON. Schema (shared by every command that prints results):
//   {"master": name,
//    "slaves": [{"name": s,
//                "q_wxyz": [w, x, y, z],      orientation of the slave in the master frame
//                "C": [x, y, z],              slave centre in the master frame, master units
//                "scale": s,                  when the slave has one scale, or else
//                "scales": [{"segment": id, "scale": s, "std": sigma}, ...],
//                "std": {"rot_deg": sigma, "pos": [sx, sy, sz]},
//                "motions_used": n, "motions_rejected": n,
//                "models": {"motion": "general"|"translational",
//                           "scale": "fixed"|"segments"|"partitions"},
//                "termination": ToString(Termination), "message": text,
//                "unobservable": [[x, y, z], ...],   unit directions, master frame
//                "errors": {"rot_deg", "dir_deg", "dist_pct", "trans_err", "scale_pct"}}]}
// Scale: slave odometry unit -> master unit. "errors" (CompareToTruth of error_model.h) is
// present only when `truth` (nullable) has an entry for the slave and the slave is usable.
// Non-finite numbers become null.
nlohmann::json ResultToJson(const RigCalibration& result,
                            const std::map<std::string, Similarity>* truth);

// Roll, pitch, yaw in degrees of the rotation R = Rz(yaw) Ry(pitch) Rx(roll) (ZYX Euler
// angles, as in ROS/Kalibr tooling); pitch in [-90, 90].
Eigen::Vector3d RollPitchYawDeg(const Eigen::Quaterniond& q);

// A text table of the result for terminals: per slave q (w, x, y, z), roll/pitch/yaw in
// degrees, C, scale(s), standard deviations, motions used/rejected, models, termination and
// message; with `truth` (nullable) the true values next to the estimates and the error model.
std::string FormatResultTable(const RigCalibration& result,
                              const std::map<std::string, Similarity>* truth);

}  // namespace rigcal::tools
