// SPDX-License-Identifier: Apache-2.0
#pragma once
// The human explanation of a slave's motion model (thesis 4.5, 5.2 and the planar model of
// model_selection.h): which model was chosen, why, and what the motions could therefore not
// determine. Written once for the batch calibrator and the recursive estimator, so both say the
// same thing in the same words.

#include <string>

#include "rigcal/base/format.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

struct ModelExplanation {
  MotionModel model = MotionModel::kGeneral;  // the chosen model: general, planar, translational
  // The figures quoted: max_rotation_deg, translational_below_deg, rotation_noise_deg,
  // planar_axis, axis_std_ratio.
  Observability figures;

  // Reasons, each stated when given.
  // The largest rotation against the equal-error boundary of thesis 5.2 (kCompared), or alone
  // (kLargestRotation: a model that was not chosen by it).
  enum class Boundary { kNone, kCompared, kLargestRotation };
  Boundary boundary = Boundary::kNone;
  // The boundary scales with the measured rotation noise (alpha_maxrot_noise_deg > 0), so the
  // noise is quoted; otherwise it is the fixed alpha_maxrot_deg.
  bool boundary_from_noise = true;
  std::string selection;  // why general or planar (RotatingSolution::why); empty: not stated

  // What follows.
  bool parallel = false;  // translational: every translation parallel (driving straight)
  // σ of C along the mean rotation axis: quoted for general motion that is nearly planar.
  double axis_offset_std = 0.0;
  // The nominal mounting: C along the planar axis taken from it (planar model), or a weighted
  // prior (nominal_sigma > 0, both models).
  bool nominal = false;
  double nominal_along_axis = 0.0;  // a^T C_nominal, master units
  double nominal_sigma = 0.0;
};

// "<model> motion (<reasons>)<consequence>", for example
//   "translational motion (largest rotation 1.20 deg < 5.00 deg, the equal-error boundary at the
//    measured rotation noise 0.250 deg): rotation and scale only, position unobservable"
//   "planar motion (<selection>): C along the rotation axis [0.000, 1.000, 0.000] is
//    unobservable, reported as 0 (unknown; a nominal mounting would fill it in)"
//   "general motion; nearly planar: C along the mean rotation axis [...] has sigma 0.0123"
std::string ExplainModel(const ModelExplanation& e);

}  // namespace rigcal::internal
