// SPDX-License-Identifier: Apache-2.0
#pragma once
// The ground truth of a simulated rig on disk (`rigcal run --truth-out DIR`):
//   <camera>.txt        TUM trajectory of the camera at every nominal frame stamp in its own
//                       reference frame (its pose at frame 0 is the identity; thesis
//                       T_i^k = (T_i,world^0)^-1 T_i,world^k), metres;
//   world_<camera>.txt  the same in the simulated world (z up);
//   truth.yaml          the true rig in the rig YAML format of rig_files.h: `master` and one
//                       entry per slave in rig order (q_wxyz, C, scale 1).

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/sim/simulated_ground_truth.h"

namespace rigcal::io {

// Writes the files above of `truth` (SimulatedRig::GroundTruth) into directory `dir` (created
// if missing), each file atomically (WriteFileAtomically). Ok, or an error naming the file or
// directory.
Status WriteGroundTruth(const sim::SimulatedGroundTruth& truth, const std::string& dir);

}  // namespace rigcal::io
