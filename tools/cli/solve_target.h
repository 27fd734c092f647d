// SPDX-License-Identifier: Apache-2.0
#pragma once
// The target and metric parts of `rigcal solve`: `--reference target` (the global reference
// pose model, thesis 4.2, from per-camera target poses), `--metric-target` (lambda_world from
// the master's target poses, 5.5) and `--master-metric` (a metric odometry master: wheel
// odometry, INS). Kept apart from solve_command.cc, which calls these.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/base/status.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::cli {

// Every slave's target reference as a result: estimate (scale 1), σ, state converged, message
// with the instants used. `individual`: each camera's poses are in its own target's frame
// (individual reference pose model, individual_reference.h), else in one shared target's frame
// (global model, σ of the mean). Errors: a slave sharing too few instants with the master
// (within tolerance_ns); for the individual model, motion that does not determine the pose.
Expected<RigCalibration> TargetReferenceResult(const TimedTrajectory& master,
                                               const std::vector<TimedTrajectory>& slaves,
                                               int64_t tolerance_ns, bool individual = false);

// What the result's positions are in, for the output (a line above the table, `unit` in the
// JSON, a comment in the result file).
struct ResultUnit {
  bool metric = false;
  double metres_per_master_unit = 1.0;  // lambda_world
  double std = 0.0;                     // its σ (0: exact by definition)
  std::string source;                   // "target", "master odometry", "target reference"
  std::string message;                  // one line
  nlohmann::json ToJson() const;
};

// --metric-target FILE: lambda_world from the master's target poses in FILE against the master
// odometry; scales `result` to metres. Errors: the file, or the fit (metric_scale.h).
Expected<ResultUnit> ApplyMetricTarget(const std::string& target_file,
                                       const TimedTrajectory& master, int64_t tolerance_ns,
                                       RigCalibration* result);

// Lines for a metric master whose slaves moved in a plane: C along the rotation axis (the
// mounting height for a vehicle on a road) is not observable; says whether the nominal
// mounting (--prior) filled it in. Empty when no slave has an unobservable direction.
std::string UnobservableHeightNote(const RigCalibration& result);

}  // namespace rigcal::cli
