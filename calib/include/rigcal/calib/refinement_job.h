// SPDX-License-Identifier: Apache-2.0
#pragma once
// The background refinement of the recursive estimator: a job copied from a slave's statistics
// (RigEstimator::MakeRefinementJob, rig_estimator.h), refined on another thread (RefineWindow)
// and handed back (RigEstimator::ApplyRefinement).

#include <atomic>
#include <cstdint>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/refinement_prior.h"

namespace rigcal {

// One slave's refinement job: a copy of the window and the linear estimate to start from.
struct RefinementJob {
  int slave = 0;
  std::vector<RigMotion> motions;
  // Per motion: how much of it the statistics still hold (exponential forgetting since it was
  // added, in (0, 1]). Its residuals are weighted by it; the robust loss replaces the Huber
  // weights of the statistics.
  std::vector<double> weights;
  SlaveCalibration start;
  uint64_t generation = 0;  // estimator generation when the job was made
  // Prior on C along start.observability.planar_axis (from the nominal mounting, when
  // options.nominal_sigma > 0): the general model adds it as a weighted term. The planar model
  // keeps C along the axis at start's value (the nominal's or 0) in any case.
  double axis_prior = 0.0;
  double axis_prior_sigma = 0.0;
  // The motions accumulated before the window (see RefinementPrior).
  RefinementPrior prior;
  // Huber loss (at 3 sigma) on the window's residuals; the prior has none.
  bool robust_loss = true;
  // The sets since the last restart (master and this slave, slaves[0], then every other slave
  // whose history holds those sets), when the pose history holds them and a history refinement
  // is due: RefineWindow then runs the batch calibrator on it with `history_options` instead of
  // refining the window, and solves this slave (the others' poses tell glitches apart, as in
  // the batch on the whole recording).
  RigRecording history;
  CalibrationOptions history_options;
  // Stream time of the newest set in `history` (when the refinement was made).
  int64_t history_t_ns = 0;
  // `history` holds every history_stride-th set of the drive (a history thinned on a drive
  // longer than it holds; RigEstimatorOptions::history_sets).
  uint64_t history_stride = 1;
  // Set by another thread to end the refinement early (CalibrationOptions::cancel): its result
  // is then not solved, only to be dropped. Null: never cancelled.
  const std::atomic<bool>* cancel = nullptr;
};

// Runs the non-linear refinement (thesis 4.26/4.27 with Ceres) of a job. Pure function:
// safe to call from a background thread on a copied job.
SlaveCalibration RefineWindow(const RefinementJob& job);

}  // namespace rigcal
