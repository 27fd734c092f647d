// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 5 of the recursive estimator (RigEstimator): the published σ. The linear solution's
// covariance takes the motions as independent; overlapping pairs and odometry drift make motions
// close in time err alike, so its σ are optimistic:
//   - overlap: every keyframe pairs with one several keyframes back, so pairs share the drift
//     between their ends. Drift makes the angle-invariant variance grow with the span: its ratio
//     between the pairs and the consecutive-keyframe motions measures the sharing, between 1
//     (errors of the poses alone, shared by the two pairs at a pose) and the mean span of the
//     pairs in keyframes (pure drift). The σ grow by its square root.
//   - rotation time blocks (rotating rig, sigma_block_s > 0): the published rotation σ is at
//     least the cluster-robust one of the time blocks (rotation_blocks.h), errors shared within
//     a block and independent between blocks.
// Convergence and the decalibration test are judged on these σ.

#include "motions/keyframe_pairing.h"
#include "noise/rotation_blocks.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

// How the pairs' errors are shared, measured on the accepted motions.
struct DriftState {
  // Angle invariant (deg^2) of the consecutive-keyframe motion ending at each new keyframe,
  // compared with that of the pairs (GateState::angle_var).
  RunningMeanSquare consecutive_angle_var;
  RunningMeanSquare pair_span;  // running mean of the pairs' span in keyframes
};

// Counts the drift figures of an accepted pair.
void RecordPairDrift(const KeyframePair& pair, DriftState* drift);

// Factors by which the linear solution's σ grow.
struct SigmaInflation {
  double overlap = 1.0;   // every σ: the square root of the overlap factor
  double rotation = 1.0;  // the rotation σ: at least `overlap` and the time blocks' factor
};

// `angle_var`: the pairs' angle-invariant variance; `rotating`: the time blocks count (a
// rotating rig).
SigmaInflation InflationOf(const RigEstimatorOptions& options, const RunningMeanSquare& angle_var,
                           const DriftState& drift, const RotationBlocks& blocks, bool rotating);

// Multiplies the σ of `published` (rotation, C, C along the axis, scales) by the factors.
void InflateSigmas(const SigmaInflation& inflation, SlaveCalibration* published);

}  // namespace rigcal::internal
