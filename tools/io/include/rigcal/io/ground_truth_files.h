#pragma once
// The ground truth of a simulated rig on disk (`rigcal run --truth-out DIR`).

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/drivers/simulated_rig.h"

namespace rigcal::io {

// Writes SimulatedRig::GroundTruthFiles() into directory `dir` (created if missing), each file
// atomically (WriteFileAtomically). Ok, or an error naming the file or directory.
Status WriteGroundTruth(const drivers::SimulatedRig& rig, const std::string& dir);

}  // namespace rigcal::io
