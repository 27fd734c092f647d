// SPDX-License-Identifier: Apache-2.0
// The published σ of the recursive estimator (online_uncertainty.h).
#include "online/online_uncertainty.h"

#include <algorithm>
#include <cmath>

namespace rigcal::internal {
namespace {

// How many pairs share each error, on average (online_uncertainty.h): the ratio of the pairs'
// angle-invariant variance to the consecutive-keyframe motions', within [1, mean span].
double OverlapFactor(const RunningMeanSquare& pairs, const RunningMeanSquare& consecutive,
                     const RunningMeanSquare& span) {
  if (pairs.count == 0 || consecutive.count == 0 || !(consecutive.value > 0.0)) return 1.0;
  return std::clamp(pairs.value / consecutive.value, 1.0, std::max(1.0, span.value));
}

}  // namespace

void RecordPairDrift(const KeyframePair& pair, DriftState* drift) {
  drift->consecutive_angle_var.Add(pair.consecutive_angle_diff_deg *
                                   pair.consecutive_angle_diff_deg);
  drift->pair_span.Add(pair.span_keyframes);
}

SigmaInflation InflationOf(const RigEstimatorOptions& o, const RunningMeanSquare& angle_var,
                           const DriftState& drift, const RotationBlocks& blocks, bool rotating) {
  SigmaInflation f;
  f.overlap = std::sqrt(OverlapFactor(angle_var, drift.consecutive_angle_var, drift.pair_span));
  f.rotation = o.sigma_block_s > 0.0 && rotating
                   ? std::max(f.overlap, std::sqrt(blocks.VarianceFactor(o.sigma_min_blocks)))
                   : f.overlap;
  return f;
}

void InflateSigmas(const SigmaInflation& f, SlaveCalibration* published) {
  published->rot_std_deg *= f.rotation;
  if (f.overlap > 1.0) {
    published->pos_std *= f.overlap;
    if (std::isfinite(published->axis_offset_std)) published->axis_offset_std *= f.overlap;
    for (SegmentScale& sc : published->scales) sc.std *= f.overlap;
  }
}

}  // namespace rigcal::internal
