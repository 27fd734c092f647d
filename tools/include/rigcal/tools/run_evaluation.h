#pragma once
// Scoring a live run on a simulated rig against its ground truth (thesis 5.1.1 error model).
//
// The estimate's positions are in the master camera's odometry unit. The unit of each VO scale
// segment is recovered from the recorded VO poses and the true trajectory (least-squares scale
// of the VO camera centres against the true ones, both in the segment's reference frame), so
// the estimate can be compared with the metric truth: distance error after scaling by the
// master's unit, and the true relative scale d_lambda = slave unit / master unit.

#include <string>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/expected.h"
#include "rigcal/calib/types.h"
#include "rigcal/drivers/simulated_rig.h"

namespace rigcal::tools {

struct SegmentUnit {
  int segment = 0;
  int poses = 0;
  double metres_per_unit = 0.0;  // least-squares scale VO -> metric
  double fit_rms_m = 0.0;        // RMS residual of the scaled VO centres, metres
};

struct SlaveEvaluation {
  std::string name;
  bool usable = false;
  int segment = 0;                // slave segment whose scale is scored
  CalibrationError error;         // q, direction, distance (%), scale (%) vs truth
  Similarity truth_master_units;  // the truth expressed in master units (for JSON errors)
};

struct RunEvaluation {
  int master_segment = 0;  // the master segment whose unit positions are expressed in
  double master_metres_per_unit = 0.0;
  std::vector<std::vector<SegmentUnit>> units;  // per camera, per segment
  std::vector<SlaveEvaluation> slaves;
  std::string note;  // e.g. the master re-initialised: positions mix units
};

// `poses[i]`: every pose camera i's VO produced (Pipeline::RecordedPoses). Fails when the
// master has no segment with at least 3 poses.
Expected<RunEvaluation> EvaluateRun(const drivers::SimulatedRig& rig,
                                    const std::vector<std::vector<CameraPose>>& poses,
                                    const RigCalibration& result);

// A table: slave, rotation error (deg), position direction error (deg), distance error (%),
// scale error (%), and the master unit.
std::string FormatEvaluation(const RunEvaluation& evaluation);

}  // namespace rigcal::tools
