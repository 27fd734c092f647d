// SPDX-License-Identifier: Apache-2.0
#pragma once
// Options of the pair choice (pair_selection.h): which pairs of times (a, b) of a recording
// become the batch calibrator's motions. Plain struct, documented defaults, Check().

#include <string>

#include "rigcal/base/status.h"

namespace rigcal {

struct PairOptions {
  enum class Policy {
    kSinceStart,  // (0, k) for every k: the thesis's camera-local poses
    kRelative,    // (k, k + step) for every k
    kAuto,        // per slave, the span whose estimate is most certain (see below)
    kWalk,        // anchors walk to a target motion (see below; the earlier default)
    kGls,         // per slave, auto's result refined by GLS on chains of its span(s) (default)
  };
  Policy policy = Policy::kGls;

  // kRelative: frames between a and b.
  int step = 5;

  // kAuto: every slave is solved with the pairs (k, k + N) of each span N of a ladder 1, 2,
  // 3, 5, 8, ... (ratio ~1.5) up to auto_max_span_fraction of the recording, and with kWalk's
  // pairs, and keeps the candidate whose reported σ are smallest: the largest of
  // σ_rot / min σ_rot and σ_C / min σ_C is minimal (rotation and position both within the
  // least factor of their best candidate; the ladder's σ smoothed over neighbouring spans). The σ
  // are the cluster-robust ones (CalibrationOptions::covariance_time_blocks, blocks at least
  // three motion durations long), so what the span gains in signal is weighed against the
  // drift and shared pose errors it accumulates, as measured on this recording. Candidate solves
  // use at most max_pairs pairs (every k-th anchor); the chosen span is solved with all.
  double auto_max_span_fraction = 0.125;
  // kGls: keep auto's result when the GLS σ of rotation and of C are both larger than auto's.
  bool gls_keep_more_certain = true;
  // kGls: when auto's candidate of the smallest rotation σ is not that of the smallest C σ, the
  // rotation from the first's chains and C and the scales from the second's, the rotation
  // carried over with its covariance (false: auto's choice refined alone).
  bool gls_mixture = true;

  // kWalk. For anchors a spread evenly over the recording, b walks forward from a until the
  // master motion a->b is "large enough": its rotation angle reaches target_angle_deg or its
  // translation reaches target_translation_fraction of the master trajectory's extent
  // (bounding-box diagonal). The walk stops at the longest useful span: twice the span whose
  // motions have the best signal-to-noise ratio (AutoPairSpan below: white pose noise favours
  // long spans, drift short ones), and never beyond max_span_fraction of the recording.
  // Pairs whose motion stays below both min_angle_deg and min_translation_fraction are not
  // used. A walk that runs into the end of the recording (or of a segment) before it reaches a
  // target or the span limit ends at that last pose, as does every later anchor's: only the
  // first such truncated pair is used (that one pose's noise would enter up to half of the
  // motions; measured on a sewer-like drive with white pose noise: 7 sigma of rotation error).
  // With max_pairs_per_end > 0, at most that many pairs end at one pose: a walk that
  // stops at a pose already ending that many (the end of a turn, the end of the recording)
  // moves on to the next free pose within the span limit, or the anchor is skipped. Shared
  // ends share their noise, so the reported σ is optimistic (measured: 3-10x on the KITTI 00
  // drive, where up to 115 pairs end at one pose); on real hand-held data (EuRoC) the limit
  // costs pairs and accuracy, hence no limit by default. Large rotations inform both rotation and
  // position ((I
  // - R_0) grows with the angle); beyond ~120 degrees the quaternion sign becomes ambiguous under
  // noise.
  double target_angle_deg = 120.0;
  double target_translation_fraction = 0.5;
  double min_angle_deg = 3.0;
  double min_translation_fraction = 0.05;
  double max_span_fraction = 0.5;
  int max_pairs = 4000;       // kWalk, kAuto's candidates: at most this many pairs
  int max_pairs_per_end = 0;  // 0 = no limit

  // Success, or the first offending field and its constraint: "<field>: <constraint>".
  Status Check() const;
};

std::string ToString(PairOptions::Policy policy);
// The pairs as the command line names them: "auto", "start", "walk", "relative:<step>".
std::string PairsText(const PairOptions& options);

}  // namespace rigcal
