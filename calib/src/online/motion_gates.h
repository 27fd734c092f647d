// SPDX-License-Identifier: Apache-2.0
#pragma once
// Stage 2 of the recursive estimator (RigEstimator): which formed motions enter the statistics,
// and with what weight. The gates are the scale-free invariants of the thesis and the residuals
// at the current estimate:
//   - small rotation: the general model does not use motions below pair_min_angle_deg (4.3.1);
//   - angle invariant: master and slave rotate by the same angle whatever the extrinsics, within
//     max(angle_gate_floor_deg, gate_sigmas * its running σ) (4 floors before gating starts);
//   - screw pitch (4.18): the scale the motion measures agrees with the current one within
//     scale_gate (relative);
//   - residuals (4.10, 4.16/4.17, 4.31) beyond gate_sigmas running σ are rejected, beyond
//     huber_sigmas Huber-weighted.
// Gating (all but the first two) starts once gate_after_motions motions were accepted in the
// current motion model. A residual gate that rejects gate_after_motions motions in a row has an
// estimate that the motions contradict (formed early, from motions about one axis, say): it is
// the estimate that is off, so gating restarts and the estimate can follow the motions.

#include <string>

#include "motions/motion_data.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/calib/rig_estimator_options.h"

namespace rigcal::internal {

// What the gates remember of a slave's accepted motions.
struct GateState {
  RunningMeanSquare angle_var;  // angle invariant |angle_0 - angle_i|^2, deg^2
  // Rotation and position residuals at the estimate, since the motion model last changed.
  RunningMeanSquare rot_var, pos_var;
  RunningMeanSquare ci_sq;    // |C_i|^2: the screw-pitch gate ignores motions that barely screw
  int accepted_in_model = 0;  // accepted motions since the motion model last changed
  int gate_rejections_in_row = 0;  // consecutive motions rejected by the residual gates
};

enum class GateVerdict { kAccepted, kSmallRotation, kAngleMismatch, kScaleMismatch, kOutlier };

struct GateOutcome {
  GateVerdict verdict = GateVerdict::kAccepted;
  double weight = 1.0;          // the accepted motion's weight (Huber, <= 1)
  double angle_diff_deg = 0.0;  // its angle invariant |angle_0 - angle_i|
  double r_rot = 0.0;           // residuals at the estimate (r_pos < 0: not computed)
  double r_pos = -1.0;
};

// Gates the motion `md` (quaternion signs aligned with the estimate). `rotating`: the general
// or planar model applies (else the translational one); `estimate`: the slave's linear estimate
// in that motion model, null when there is none. Pure.
GateOutcome GateMotion(const RigEstimatorOptions& options, const GateState& state,
                       const MotionData& md, bool rotating, const SlaveCalibration* estimate);

// Counts an accepted motion into the noise levels (the residual ones only with an estimate).
void RecordAccepted(const GateOutcome& outcome, const MotionData& md, bool have_estimate,
                    GateState* state);

// Counts a motion rejected by a residual gate (screw pitch or residuals). The
// gate_after_motions-th in a row restarts the residual gating (logged for `slave_name`).
void RecordResidualRejection(const RigEstimatorOptions& options, const std::string& slave_name,
                             GateState* state);

// Residual gating starts afresh (the motion model changed, or the estimate is off): gating
// waits for gate_after_motions accepted motions and the residual noise levels restart.
void RestartResidualGating(GateState* state);

}  // namespace rigcal::internal
