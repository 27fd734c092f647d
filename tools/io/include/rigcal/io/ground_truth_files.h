#pragma once
// The ground truth of a simulated rig on disk (`rigcal run --truth-out DIR`).

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::tools {

// Writes SimulatedRig::GroundTruthFiles() into directory `dir` (created if missing), each file
// atomically (WriteFileAtomically). Ok, or an error naming the file or directory.
Status WriteGroundTruth(const sim::SimulatedRig& rig, const std::string& dir);

}  // namespace rigcal::tools
