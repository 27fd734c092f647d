// SPDX-License-Identifier: Apache-2.0
#pragma once
// Contiguous time blocks of motions, for covariances that let motions close in time share
// their errors (overlapping pairs share poses, odometry drifts, pose errors of neighbouring
// frames are correlated): errors are taken as independent between blocks only.

#include <vector>

#include "motions/motion_data.h"

namespace rigcal::internal {

// Block (0 .. blocks-1) of each motion: within every scale variable (scale_index) its motions
// in time order (t_ns) are cut into `blocks` runs of equal count, so that every block holds a
// share of every scale variable.
std::vector<int> TimeBlocks(const std::vector<MotionData>& motions, int blocks);

// How many blocks (at most `max_blocks`) keep the motions that share errors mostly within one
// block: a motion shares poses and drift with every motion overlapping it in time, so a block
// lasts at least three times the median motion duration. Never fewer than 4 (the sandwich
// needs a few independent blocks; with fewer the σ of such long motions is optimistic).
int BlocksForDurations(const std::vector<MotionData>& motions, int max_blocks);

}  // namespace rigcal::internal
