#pragma once
// The auto pair policy of the batch calibrator (PairOptions::Policy::kAuto): per slave, the
// span whose solve reports the most certain estimate.

#include <string>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/types.h"

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
// among the usable results when there are any (a thinned span solved again with every k). The
// result's `pairs` names the candidate and its message how it was chosen.
SlaveCalibration CalibrateSlaveAutoPairs(const RigRecording& recording,
                                         const AutoPairCandidates& candidates, int slave,
                                         const CalibrationOptions& options);

}  // namespace rigcal::internal
