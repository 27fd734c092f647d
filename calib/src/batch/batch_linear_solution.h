// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 3 of the batch calibrator (CalibrateSlave): the linear estimate (thesis 4.3: rotation
// 4.9-4.11, position and scales 4.14-4.17; translational model 4.29-4.32; planar model
// planar_solver.h) with misfit removal: rounds of solve, residuals, outlier test.

#include <Eigen/Geometry>
#include <vector>

#include "models/linear_solvers.h"
#include "models/model_selection.h"
#include "motions/motion_data.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// What the batch calibration of one slave solves for, fixed before the motions are solved.
struct BatchSetting {
  MotionModel requested = MotionModel::kAuto;  // kAuto made translational below the boundary
  bool translational = false;                  // requested == kTranslational
  ModelSelectionOptions select;  // options.model_selection: general or planar (model_selection.h)
  AxisPrior prior;  // the nominal mounting's C along the mean rotation axis, when given
  // The prior's offset along `axis` (0 without a prior).
  double AxisPriorAlong(const Eigen::Vector3d& axis) const {
    return prior.given ? axis.dot(prior.nominal_C) : 0.0;
  }
};

// The linear solution of a rotating rig (general or planar, model_selection.h) with the
// quaternion signs of the motions aligned to it. `scales` is indexed by scale_index.
struct RotatingFit {
  RotatingSolution solution;
  std::vector<double> scales;
};
RotatingFit SolveRotatingLinear(std::vector<MotionData>* motions, int num_scales,
                                const BatchSetting& setting);

// Scales of `n` scale variables (scale_index of the motions) from the position equations
// (empty when a rotating rig's are singular).
std::vector<double> SolveScales(std::vector<MotionData>* motions, int n,
                                const BatchSetting& setting);

// Maps the scale keys present to consecutive scale indices; returns the keys in index order.
std::vector<int> CompactScaleIndices(std::vector<MotionData>* motions);

struct LinearEstimate {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  LinearPositionScale pos;      // C (0 for the translational model) and the scales
  std::vector<int> scale_keys;  // the scale key of each scale index
  RotatingFit fit;              // rotating rig: the solution with its figures
};

// The linear estimate of the motions (scale keys assigned), with up to max_outlier_rounds
// rounds of misfit removal: position residuals beyond outlier_mad_factor robust σ (then the
// rotation residuals, when no position residual is) are removed and counted as residual
// outliers, until none is or fewer than min_motions remain.
LinearEstimate SolveLinear(const CalibrationOptions& options, const BatchSetting& setting,
                           std::vector<MotionData>* motions, MotionCounts* counts);

}  // namespace rigcal::internal
