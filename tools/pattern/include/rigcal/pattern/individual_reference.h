// SPDX-License-Identifier: Apache-2.0
#pragma once
// Target-based reference rig calibration with the individual reference pose model (thesis 4.2,
// fig. 4.4; the two-pattern setup of 5.7): every camera sees its own fixed target, so camera i's
// pose T_i^k is known in its own target frame. With W_i the (unknown, fixed) pose of target i
// in target 0's frame, every instant k gives
//     T_0^k dT_i = W_i T_i^k,
// which is the thesis's (T_0^0)^-1 T_0^k dT_i = dT_i (T_i^0)^-1 T_i^k with W_i eliminated.
// Both targets are metric, so the scale is 1.
//
// Estimate: dR from the rotation vectors of the motions relative to the first instant
// (alpha = dR beta, Kabsch), dC from (R_A - I) dC = dR C_B - C_A (least squares), W_i from the
// instants; then (dT_i, W_i) refined jointly by least squares on every instant's residual
// (rotation log and centre difference of the two sides, each whitened by its RMS), instants
// whose residual exceeds median + 5 * 1.4826 * MAD dropped once. σ: the inverse of the
// whitened normal matrix (Gauss-Newton covariance): a lower bound when the instants' errors
// are correlated (consecutive frames of a video).
//
// The motion must rotate about two different axes: rotation about one axis leaves dC along it
// undetermined (the error says so).

#include <cstdint>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/pattern/reference_calibration.h"

namespace rigcal::pattern {

struct IndividualReference {
  ReferenceEstimate estimate;            // dT_i, its σ, residual RMS as spread, instants
  Pose master_target_from_slave_target;  // W_i
};

// Stamps paired within `tolerance_ns`. Errors: fewer than 4 paired instants, motion without
// two distinct rotation axes, a singular covariance.
Expected<IndividualReference> EstimateIndividualReference(const TimedTrajectory& master,
                                                          const TimedTrajectory& slave,
                                                          int64_t tolerance_ns);

}  // namespace rigcal::pattern
