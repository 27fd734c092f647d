// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one comparison of an estimate with a truth (thesis 5.1.1 error model), used by
// `rigcal run --eval`, `solve --truth`, `replay`/`calib` with a truth and `report --truth`.
//
// Positions of an estimate are in the unit of the master odometry segment the estimate is
// expressed in: a non-metric master that re-initialises opens a new segment with a new unit,
// and the estimator restarts positions and scales in it (rig_estimator_options.h,
// master_metric). A metric truth is brought into that unit:
//   - with the odometry poses and the true trajectories of the cameras, per segment: the unit of
//     every segment of every camera is the least-squares scale of its odometry centres against
//     the true ones (FitSegmentUnits); the master unit is the unit of the estimate's segment (the
//     newest master segment), a slave's true scale the unit of its scored segment over it;
//   - without them, from the mountings alone (AlignTruthUnit, truth_alignment.h); a slave's
//     odometry unit is then unknown and no scale error is given.
// A truth in master units (TruthUnit::kMaster, or kAuto deciding so) is compared as given.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/timed_trajectory.h"
#include "rigcal/io/truth_alignment.h"

namespace rigcal::io {

// The unit of one odometry segment of one camera.
struct SegmentUnit {
  int segment = 0;
  int poses = 0;
  double metres_per_unit = 0.0;  // least-squares scale odometry -> metres
  double fit_rms_m = 0.0;        // RMS residual of the scaled odometry centres, metres
};

// A camera's true pose (world_from_cam, metres, any fixed world frame) at t_ns; nullopt where
// the truth has none.
using TrueTrajectory = std::function<std::optional<Pose>(int64_t t_ns)>;

// The unit of every segment of `poses` (one camera's odometry): positions relative to the
// segment's first pose on both sides (the odometry's origin need not be its first pose written),
// fitted by least squares. Poses without a true pose are left out; a segment with fewer than 2
// poses gets metres_per_unit 0.
std::vector<SegmentUnit> FitSegmentUnits(const std::vector<CameraPose>& poses,
                                         const TrueTrajectory& truth);

// A TrueTrajectory over a sampled true trajectory (e.g. a TUM file of `run --truth-out`): the
// centre interpolated linearly between the samples around t_ns, the rotation of the nearer one;
// nullopt outside the samples or across a gap of more than 3 median sample intervals.
TrueTrajectory SampledTrajectory(TimedTrajectory samples);

// What a comparison is given.
struct TruthInput {
  std::map<std::string, Similarity> mountings;  // per slave name, as `unit` says
  TruthUnit unit = TruthUnit::kAuto;
  // Optional, per camera in rig order (master first): its odometry poses and its true
  // trajectory. Without the master's both, the unit is fitted from the mountings.
  std::vector<std::vector<CameraPose>> poses;
  std::vector<TrueTrajectory> trajectories;
};

// One slave compared.
struct SlaveScore {
  std::string name;
  bool usable = false;
  int segment = 0;  // the slave segment whose scale is scored (its newest)
  // Rotation, direction, distance (%), scale (%, NaN when the slave's unit is unknown). When the
  // estimate leaves the offset along an axis undetermined (planar motion without a prior),
  // direction and distance compare the components in the plane orthogonal to it; plane_err /
  // axis_err split |C - C_hat| at the axis (master units).
  CalibrationError error;
  Similarity truth_master_units;  // the truth in master units; scale NaN when unknown
  bool position_observable = true;
  bool axis_unknown = false;
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
};

struct TruthComparison {
  TruthAlignment alignment;  // what was aligned and how (message)
  // The master segment the estimate is expressed in, and the master's segments seen; -1 and 0
  // without odometry poses.
  int master_segment = -1;
  int master_segments = 0;
  double master_metres_per_unit = 1.0;          // 1 when not aligned
  std::vector<std::vector<SegmentUnit>> units;  // per camera, per segment (with trajectories)
  std::vector<SlaveScore> slaves;               // per slave of the result with a truth
  std::string note;                             // e.g. which master segment was used and why
  // The truth per slave in master units (for ResultToJson / FormatResultTable).
  std::map<std::string, Similarity> truth_master_units;
};

// Compares `result` with `input`. Fails when the master's poses and trajectory are given but no
// master segment has 3 poses with a true pose.
Expected<TruthComparison> CompareWithTruth(const RigCalibration& result, const TruthInput& input);

// Fills the score's error, position_observable, axis and axis_unknown from the slave's estimate
// (with the scale of the scored segment) against score->truth_master_units.
void ScoreSlave(const SlaveCalibration& slave, SlaveScore* score);

// The scale the score compares: the newest segment's, else the estimate's.
double ScoredScale(const SlaveCalibration& slave, int* segment);

// A table: slave, rotation error (deg), direction error (deg), distance error (%), scale error
// (%, "-" when the slave's unit is unknown), position errors in the plane and along the axis of
// planar motion (mm when metric), then what was aligned. "unobs": not determined by the motion.
std::string FormatTruthComparison(const TruthComparison& comparison);

}  // namespace rigcal::io
