// SPDX-License-Identifier: Apache-2.0
#pragma once
// The auto pair policy of the batch calibrator (PairOptions::Policy::kAuto): per slave, the
// span whose solve reports the most certain estimate.

#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/pair_selection.h"

namespace rigcal::internal {

// The pairs auto compares, the same for every slave of a recording: (k, k + N) for every span
// N of AutoSpanCandidates (every `stride`-th k, at most max_pairs), and kWalk's pairs.
struct AutoPairCandidates {
  std::vector<PairOptions> policies;  // relative:N ..., walk
  std::vector<std::vector<IndexPair>> pairs;
  int stride = 1;
};
AutoPairCandidates MakeAutoPairCandidates(const RigRecording& recording,
                                          const PairOptions& options);

// Solves slave `slave` of `recording` with each candidate's pairs and returns the result whose
// largest σ ratio to the best candidate (rotation; position when observable) is smallest,
// among the usable results when there are any (a thinned span solved again with every k).
// The σ compared are predicted, not the reported ones: each span's σ of independent motions
// (precise: every motion's residual counts) times a design effect (1 + ρN²)/(1 + ρN) for
// errors shared by overlapping motions of N poses (odometry drift), with ρ and a common level
// fitted to every span's cluster-robust σ at once (the cluster-robust σ of one long span rests
// on a few time blocks and is too noisy to rank spans by). The result's `pairs` names the
// candidate and its message how it was chosen.
// When the candidate of the smallest predicted rotation σ is not the one of the smallest
// position σ, `ranking` (optional) receives both (solved with every k; differ set).
struct AutoPairRanking {
  bool differ = false;
  SlaveCalibration rotation;
  SlaveCalibration position;
};
SlaveCalibration CalibrateSlaveAutoPairs(const RigRecording& recording,
                                         const AutoPairCandidates& candidates, int slave,
                                         const CalibrationOptions& options,
                                         AutoPairRanking* ranking = nullptr);

}  // namespace rigcal::internal
