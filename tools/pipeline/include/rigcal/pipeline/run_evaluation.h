// SPDX-License-Identifier: Apache-2.0
#pragma once
// Scoring a live run on a simulated rig against its ground truth: the one truth comparison of
// io/truth_comparison.h with the simulated rig's true trajectories, so the master unit is the
// unit of the master segment the estimate is expressed in (after a master re-initialisation the
// newest one) and every slave's true scale the unit of its scored segment over it.

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/io/truth_alignment.h"
#include "rigcal/io/truth_comparison.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::pipeline {

using SegmentUnit = io::SegmentUnit;
using SlaveEvaluation = io::SlaveScore;
using RunEvaluation = io::TruthComparison;

// `poses[i]`: every pose camera i's VO produced (Pipeline::RecordedPoses). Fails when the
// master has no segment with at least 3 poses.
Expected<RunEvaluation> EvaluateRun(const sim::SimulatedRig& rig,
                                    const std::vector<std::vector<CameraPose>>& poses,
                                    const RigCalibration& result);

// The rig's true trajectory of camera `camera` (world_from_cam at a device stamp).
io::TrueTrajectory SimulatedTrajectory(const sim::SimulatedRig& rig, int camera);

// The master unit of the run as a truth alignment (for ResultToJson).
inline io::TruthAlignment AlignmentOf(const RunEvaluation& evaluation) {
  return evaluation.alignment;
}

// io::FormatTruthComparison.
inline std::string FormatEvaluation(const RunEvaluation& evaluation) {
  return io::FormatTruthComparison(evaluation);
}

}  // namespace rigcal::pipeline
