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

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/io/truth_alignment.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::pipeline {

struct SegmentUnit {
  int segment = 0;
  int poses = 0;
  double metres_per_unit = 0.0;  // least-squares scale VO -> metric
  double fit_rms_m = 0.0;        // RMS residual of the scaled VO centres, metres
};

struct SlaveEvaluation {
  std::string name;
  bool usable = false;
  int segment = 0;  // slave segment whose scale is scored
  // q, direction, distance (%), scale (%) vs truth. When the estimate leaves the offset along
  // an axis undetermined (planar motion without a prior), direction and distance compare the
  // components in the plane orthogonal to that axis; plane_err / axis_err split |C - C_hat|
  // at the axis (master units).
  CalibrationError error;
  Similarity truth_master_units;    // the truth expressed in master units (for JSON errors)
  bool position_observable = true;  // false: translational motion, C not estimated
  bool axis_unknown = false;        // planar, the offset along `axis` neither estimated nor given
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  // planar: the unobservable direction
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
Expected<RunEvaluation> EvaluateRun(const sim::SimulatedRig& rig,
                                    const std::vector<std::vector<CameraPose>>& poses,
                                    const RigCalibration& result);

// Fills e->error, position_observable, axis and axis_unknown from the slave's estimate (with
// the scale of the scored segment) against e->truth_master_units.
void ScoreEstimate(const SlaveCalibration& slave, double estimated_scale, SlaveEvaluation* e);

// The master unit of the run as a truth alignment (for ResultToJson): applied, the unit of
// the master's scored VO segment (FitUnit of its poses against the true trajectory).
io::TruthAlignment AlignmentOf(const RunEvaluation& evaluation);

// A table: slave, rotation error (deg), position direction error (deg), distance error (%),
// scale error (%), position error in the plane and along the axis of planar motion (mm), and
// the master unit. Figures the estimate does not determine are shown as "unobs".
std::string FormatEvaluation(const RunEvaluation& evaluation);

}  // namespace rigcal::pipeline
