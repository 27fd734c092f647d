// SPDX-License-Identifier: Apache-2.0
#pragma once
// Comparing an estimate with a truth in another unit: the least-squares unit of odometry
// positions against metric ones (`rigcal run --eval`: a VO segment against the true
// trajectory; `rigcal solve --truth`: the estimated slave centres against the truth's), and
// the decision whether a truth file is in metres or already in the master's unit.

#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::io {

// k minimising sum_i |metric_i - k * in_unit_i|^2 (metres per odometry unit; 0 when every
// in_unit vector is zero) and the RMS length of the residuals metric_i - k * in_unit_i.
struct UnitFit {
  double metres_per_unit = 0.0;
  double fit_rms_m = 0.0;  // RMS over the vectors of |metric - k * in_unit|
  int count = 0;           // vectors fitted
};
UnitFit FitUnit(const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& metric_and_unit);

// What unit a truth file (--truth) is in.
enum class TruthUnit {
  kAuto,    // the master's unit when the fitted unit is 1 within 3 σ (or 2 %), else metres
  kMetric,  // metres: always aligned (the master odometry's unit is fitted)
  kMaster,  // the master's odometry unit: compared as given, never aligned
};
const char* ToString(TruthUnit unit);
// "auto", "metric", "master"; false for anything else.
bool ParseTruthUnit(const std::string& text, TruthUnit* unit);

// How the truth was brought into the estimate's unit.
struct TruthAlignment {
  TruthUnit mode = TruthUnit::kAuto;
  // True: the truth's C and scales were divided by metres_per_unit before comparing.
  bool applied = false;
  // The fitted unit: 1 master unit = metres_per_unit truth units (metres), from the truth's C
  // against the estimated C of slaves_used (least squares over the position vectors; for a
  // planar slave without a nominal mounting only the components in the plane). NaN when no
  // slave has both an estimated position and a truth.
  double metres_per_unit = std::numeric_limits<double>::quiet_NaN();
  // Its standard deviation: the larger of the estimate's position σ propagated and the fit's
  // own scatter (NaN when unknown).
  double std = std::numeric_limits<double>::quiet_NaN();
  double fit_rms_m = std::numeric_limits<double>::quiet_NaN();  // per slave, truth units
  std::vector<std::string> slaves_used;
  // A slave left out of the fit (at least 3 slaves with positions): its C disagrees with the
  // unit the others give by more than 5 times their scatter and 1 % of its distance.
  std::string slave_excluded;
  // One line: what was done and why ("positions compared after aligning the master unit to
  // the truth: 1 master unit = ... m (...)" or why not).
  std::string message;
};

// Fits the unit over the usable slaves of `result` that have a truth entry and an estimated
// position, and decides by `mode` whether to apply it.
TruthAlignment AlignTruthUnit(const RigCalibration& result,
                              const std::map<std::string, Similarity>& truth, TruthUnit mode);

// The truth in the estimate's unit: C / metres_per_unit when the alignment is applied, the
// scale then NaN (a slave's odometry unit is not known from the mountings alone: the per-segment
// comparison of truth_comparison.h knows it from the true trajectories); else as given.
std::map<std::string, Similarity> TruthInMasterUnits(const std::map<std::string, Similarity>& truth,
                                                     const TruthAlignment& alignment);

}  // namespace rigcal::io
