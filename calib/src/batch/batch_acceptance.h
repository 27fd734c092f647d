// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 6 of the batch calibrator (CalibrateSlave): whether the data support the estimate
// (slave_state.h: usable only then). Three criteria, each a statement about the data, not
// about the solver:
//   1. enough independent motions for the model's parameters, with redundancy left for a
//      residual test;
//   2. rotation residuals consistent with the rotation noise measured independently of the
//      extrinsics (a robust χ² test, batch_acceptance.cc);
//   3. every parameter of the model determined (σ from the covariance not larger than the
//      parameter's range allows).
// A failed criterion leaves the estimate in the result but makes the state initialising, and
// the message says which criterion failed and by how much.

#include <optional>
#include <string>
#include <vector>

#include "batch/batch_linear_solution.h"
#include "motions/motion_data.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::internal {

// Independent motions among `motions`: the rank of their pose graph (poses = the distinct
// pose times t_a_ns / t_b_ns, motions = edges), i.e. poses minus connected components. Motions
// that share poses (overlapping or chained pairs) add no more than the poses they bring.
int IndependentMotions(const std::vector<MotionData>& motions);

// The figures of the rotation residual test (batch_acceptance.cc).
struct RotationConsistency {
  double noise_deg = 0.0;     // ε: robust σ of master-minus-slave rotation angles
  double residual_deg = 0.0;  // robust per-axis scale of the residual rotations
  double ratio = 0.0;         // residual_deg / max(ε, floor)
  double limit = 0.0;         // largest ratio accepted
  bool consistent = true;
  // The pairing test (rotating rig): the robust residual scale with the slave's motions paired
  // with the master's motions of other times, over residual_deg (the best of a few shifts);
  // related trajectories need at least pairing_limit.
  double pairing_ratio = 0.0;
  double pairing_limit = 0.0;
  bool related = true;
};

// The residual rotations dq⁻¹ q0 dq qi⁻¹ of `motions` under the rotation `q`, tested against
// the rotation noise measured from the same motions; `rotating`: also the pairing test;
// `independent`: the independent motions among them (IndependentMotions).
RotationConsistency TestRotationResiduals(const std::vector<MotionData>& motions,
                                          const Eigen::Quaterniond& q, bool rotating,
                                          int independent);

// The translation pairing test of the translational model (C0 = λ dR Ci, eq. 4.29): the
// robust residual |C0 − λ dR Ci| with the actual pairing against the master's motions of other
// times; `scales`: λ per motion.
struct TranslationPairing {
  double residual = 0.0;  // median |C0 − λ dR Ci|, master units
  double ratio = 0.0;     // the best shifted pairing's median over `residual`
  double limit = 3.0;
  bool related = true;
};
TranslationPairing TestTranslationPairing(const std::vector<MotionData>& motions,
                                          const Eigen::Quaterniond& q,
                                          const std::vector<double>& scales);

// Criterion 3 alone: a parameter of `r` the motions do not determine (rotation σ above 10°, a
// scale's σ above 50 % of it, a scale that is not positive), or nullopt.
std::optional<std::string> UndeterminedReason(const SlaveCalibration& r);

// Why the data do not support the solved estimate `r` (fitted to `motions` under `setting`),
// or nullopt when they do; `contradiction` (nullable) is set when the reason is that the data
// contradict the model (criterion 2 or the planar model's axes), not merely too few motions or
// an undetermined parameter.
std::optional<std::string> UnsupportedReason(const CalibrationOptions& options,
                                             const BatchSetting& setting,
                                             const std::vector<MotionData>& motions,
                                             const SlaveCalibration& r,
                                             bool* contradiction = nullptr);

// The same for the online estimator's published estimate, on the motions of its window
// (statistics_accumulation.h): at least 4 independent motions, and the rotation tests (rotating
// rig) or the translation pairing test (translational model). nullopt when supported. (The
// estimator tests UndeterminedReason on every published estimate besides.)
std::optional<std::string> OnlineUnsupportedReason(const std::vector<MotionData>& window,
                                                   const SlaveCalibration& published);

}  // namespace rigcal::internal
