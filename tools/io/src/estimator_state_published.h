// SPDX-License-Identifier: Apache-2.0
#pragma once
// The published part of a slave's block in the estimator state file (version 6 and later,
// SlavePublishedState): the estimate as last published and what its σ rest on, after the slave's
// short statistics.
//
//   published
//   online <flags> <segment> <last_update_ns> <short_long_rot_deg> <keyframes> <gated_scale>
//          <decalibration_events>
//   decalibration <disagreements> <disagree_since_ns> <decalibrated_at_ns>   (version 7: the
//          decalibration alarm, DecalibrationAlarmState; a version-6 block has none)
//   drift <value> <count> <value> <count>         (pairs' consecutive angle variance, span)
//   forget <log_decay> <last_decay_ns>
//   convergence <stable> <qw> <qx> <qy> <qz>
//   glitches <position> <rotation> <angle> <in_master> <in_slave>
//   blocks <block_ns> <count>, then per block: block <start_ns> <weight> <16 numbers of AᵀA>
//   calibration            the published SlaveCalibration (WriteCalibration)
//   refined <0|1> <from_history 0|1>, then the refinement's calibration when 1
//   end
//
// Numbers are written with 17 significant digits (an exact round trip); an unknown σ is "nan".

#include <iosfwd>
#include <string_view>

#include "rigcal/base/status.h"
#include "rigcal/calib/estimator_state.h"

namespace rigcal::io::internal {

void WritePublished(std::ostream& out, const SlavePublishedState& state);

// `text`: the block from "published" to "end" of a state file of `version`. Errors name the field
// that is malformed or out of range (a rotation that is not a unit quaternion, a negative σ, an
// unknown state).
Status ReadPublished(std::string_view text, int version, SlavePublishedState* state);

}  // namespace rigcal::io::internal
