// SPDX-License-Identifier: Apache-2.0
#pragma once
// Why `rigcal calib` / `replay` calibrated nothing when no pose set reached the estimator: the
// true reason, not only that nothing usable arrived.

#include <string>
#include <vector>

#include "rigcal/pipeline/calib_node.h"

namespace rigcal::cli {

// In order: nothing received (live) or no events (log); a camera whose VO never initialised
// (image replay); every pose already consumed by a resumed state; stamps that never coincide
// within the tolerance (a pointer to `estimator.time_offset: auto`); poses refused as late, out
// of order or duplicate; else the channels the log holds. Names the cameras.
std::string NoSetsReason(const std::string& log_path, const std::vector<std::string>& names,
                         const pipeline::CalibNodeSummary& summary);

}  // namespace rigcal::cli
