#pragma once
// Which pairs of times (a, b) become motions. The rig constraint
// T_0^{a->b} dT = dT T_i^{a->b} holds for any pair, so the choice is free; it changes the
// error by an order of magnitude (short pairs: pose noise dominates the small motion;
// long pairs: accumulated odometry drift dominates).

#include <string>
#include <vector>

#include "rigcal/calib/types.h"

namespace rigcal {

struct PairOptions {
  enum class Policy {
    kSinceStart,  // (0, k) for every k: the thesis's camera-local poses
    kRelative,    // (k, k + step) for every k
    kAuto,        // information-driven, see below (default)
  };
  Policy policy = Policy::kAuto;

  // kRelative: frames between a and b.
  int step = 5;

  // kAuto. For anchors a spread evenly over the recording, b walks forward from a until the
  // master motion a->b is "large enough": its rotation angle reaches target_angle_deg or its
  // translation reaches target_translation_fraction of the master trajectory's extent
  // (bounding-box diagonal). A pair whose span would exceed max_span_fraction of the
  // recording stops there (bounded drift). Pairs whose motion stays below both
  // min_angle_deg and min_translation_fraction are not used.
  double target_angle_deg = 30.0;
  double target_translation_fraction = 0.5;
  double min_angle_deg = 3.0;
  double min_translation_fraction = 0.05;
  double max_span_fraction = 0.25;
  int max_pairs = 4000;  // anchors are thinned to at most this many pairs

  // Empty when valid, else the offending field and constraint.
  bool Check(std::string* error) const;
};

struct IndexPair {
  int a = 0;
  int b = 0;
};

// Pairs (a, b), a < b, of indices into `recording`. Pairs never cross a scale segment
// boundary of the master; slave boundaries are handled by MotionsForSlave.
std::vector<IndexPair> SelectPairs(const RigRecording& recording, const PairOptions& options);

// The motions of slave `slave_index` for the given pairs. A pair whose ends lie in different
// slave segments is skipped (its scale is undefined).
std::vector<RigMotion> MotionsForSlave(const RigRecording& recording, int slave_index,
                                       const std::vector<IndexPair>& pairs);

std::string ToString(PairOptions::Policy policy);

}  // namespace rigcal
