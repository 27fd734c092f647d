// SPDX-License-Identifier: Apache-2.0
#pragma once
// The truth a command compares its estimate with (`--truth` of solve and report, a rig config's
// cameras[].truth for calib and replay): read once here and compared by io::CompareWithTruth
// (truth_comparison.h), so every command prints the same errors for the same estimate and truth.

#include <map>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/timed_trajectory.h"
#include "rigcal/io/truth_comparison.h"

namespace rigcal::io {

// `path`: a rig YAML (truth or result), a rig config whose cameras carry `truth`, or a directory
// written by `rigcal run --truth-out` (truth.yaml and a TUM trajectory <camera>.txt per camera):
// then the true trajectories of `cameras` are read too, and the master unit is aligned per master
// segment. Errors name the file, line and field.
struct TruthFiles {
  std::map<std::string, Similarity> mountings;
  std::map<std::string, TrueTrajectory> trajectories;  // by camera name
};
Expected<TruthFiles> ReadTruthFiles(const std::string& path,
                                    const std::vector<std::string>& cameras = {});

// The comparison of `result` with `truth`: `odometry` (rig order, master first) are the poses
// the estimate was computed from, used with the true trajectories when there are any.
Expected<TruthComparison> CompareRunWithTruth(const RigCalibration& result, const TruthFiles& truth,
                                              TruthUnit unit,
                                              const std::vector<TimedTrajectory>& odometry);

}  // namespace rigcal::io
