// SPDX-License-Identifier: Apache-2.0
#pragma once
// Which pairs of times (a, b) become motions (the policies: pair_options.h). The rig constraint
// T_0^{a->b} dT = dT T_i^{a->b} holds for any pair, so the choice is free; it changes the
// error by an order of magnitude (short pairs: pose noise dominates the small motion;
// long pairs: accumulated odometry drift dominates).

#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/pair_options.h"

namespace rigcal {

struct IndexPair {
  int a = 0;
  int b = 0;
};

// Pairs (a, b), a < b, of indices into `recording`. Pairs never cross a scale segment
// boundary of the master; slave boundaries are handled by MotionsForSlave. kAuto is resolved
// per slave by CalibrateRig (it solves each candidate span); here it gives kWalk's pairs.
std::vector<IndexPair> SelectPairs(const RigRecording& recording, const PairOptions& options);

// The motions of slave `slave_index` for the given pairs. A pair whose ends lie in different
// slave segments is skipped (its scale is undefined).
std::vector<RigMotion> MotionsForSlave(const RigRecording& recording, int slave_index,
                                       const std::vector<IndexPair>& pairs);

// The spans kAuto tries on a recording of `poses` poses (ascending, at least {1}).
std::vector<int> AutoSpanCandidates(int poses, const PairOptions& options);

// Pairs (k, k + span) for every stride-th k within one master segment (kRelative for
// stride 1).
std::vector<IndexPair> RelativePairs(const RigRecording& recording, int span, int stride = 1);

// The span (in poses) that kWalk uses when the rig rotates: among the spans 1, 2, 4, ... up to
// max_span_fraction of the recording, the one whose motions have the best ratio of master
// rotation angle (capped at target_angle_deg) to scale-free noise (the spread of the
// difference of master and slave rotation angles, which must be equal). White pose noise
// favours long spans, accumulating drift short ones. 0 when the rig hardly rotates (median
// angle below min_angle_deg at every span): kWalk then walks by translation instead.
int AutoPairSpan(const RigRecording& recording, const PairOptions& options);

}  // namespace rigcal
