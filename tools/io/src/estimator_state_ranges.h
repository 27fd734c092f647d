// SPDX-License-Identifier: Apache-2.0
#pragma once
// Range checks of a parsed estimator state beyond its checksum: a hand-edited file with a valid
// checksum must not feed negative counts or absurd sums (1e300) to the estimator.

#include "rigcal/calib/estimator_state.h"
#include "rigcal/base/status.h"

namespace rigcal::io {

// Largest magnitude of any saved number: sums of squared positions over millions of motions stay
// far below it, and its square is still finite.
inline constexpr double kMaxStateMagnitude = 1e100;

// Ok, or "slave <name> long: weight = -1 is out of range [0, 1e+100]" naming the first value out
// of range.
Status CheckEstimatorStateRanges(const RigEstimatorState& state);

}  // namespace rigcal::io
