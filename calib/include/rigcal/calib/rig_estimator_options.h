// SPDX-License-Identifier: Apache-2.0
#pragma once
// Options of the recursive estimator (RigEstimator, rig_estimator.h): plain struct, documented
// defaults, Check().

#include <cstdint>
#include <optional>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/model_selection_options.h"

namespace rigcal {

struct RigEstimatorOptions {
  // Keyframes (per slave): a set becomes a keyframe when the master has rotated by
  // keyframe_min_angle_deg since the last keyframe, or moved as far as its median speed (over
  // the last 2 keyframe_max_interval_ns) carries it in keyframe_min_travel_s (a distance in
  // the master's own unit, which a monocular VO sets arbitrarily: motions/master_travel.h), or
  // keyframe_max_interval_ns has passed. 0.04 s: at 20-25 Hz a keyframe at every set while the
  // master moves at 80-100 % of its median speed or faster, every other one while slower (as
  // the former 0.05 master units did in a VO's usual unit, without depending on it).
  double keyframe_min_angle_deg = 2.0;
  double keyframe_min_travel_s = 0.04;
  int64_t keyframe_max_interval_ns = 1'000'000'000;
  int keyframe_history = 64;  // keyframes kept per slave to pair with

  // Motion pairs: each new keyframe b pairs with the latest older keyframe a for which the
  // master motion a->b reaches pair_target_angle_deg or pair_target_translation_fraction of
  // the extent of the keyframe history, within pair_max_span_ns (bounded drift).
  double pair_target_angle_deg = 30.0;
  double pair_target_translation_fraction = 0.5;
  int64_t pair_max_span_ns = 30'000'000'000;
  double pair_min_angle_deg = 2.0;  // general model: smaller motions are not used

  // Gating (after gate_after_motions accepted motions): rotation-angle invariant within
  // max(angle_gate_floor_deg, gate_sigmas * running sigma); screw-pitch scale (4.18) within
  // scale_gate (relative) of the current scale; residuals beyond gate_sigmas rejected and
  // Huber-weighted beyond huber_sigmas.
  int gate_after_motions = 15;
  double angle_gate_floor_deg = 0.5;
  double gate_sigmas = 6.0;
  double huber_sigmas = 2.5;
  double scale_gate = 0.3;

  // Forgetting: half-life of the information, seconds of stream time (0 = never forget).
  double half_life_s = 0.0;
  // Short-window twin for decalibration detection.
  double short_half_life_s = 20.0;
  double decalibration_sigmas = 5.0;
  double decalibration_min_deg = 0.5;
  double decalibration_min_translation = 0.0;  // 0 = only rotation triggers
  int decalibration_confirmations = 3;         // consecutive keyframes in disagreement
  // ... holding for at least this much stream time (keyframes come at the rate of the motion:
  // 3 at 30 Hz are 0.1 s). A motion of unusual leverage can pull the short window away for a
  // fraction of a second (measured: up to 0.5 s of 1.5° on slow VO drift); a moved camera keeps
  // it away until the alarm, which this delays by at most 1 s, 5 % of short_half_life_s.
  double decalibration_confirm_s = 1.0;

  // Odometry segments kept open (their scale is a variable); older ones are marginalised.
  int max_open_segments = 2;

  // The master odometry is metric (wheel odometry, INS; a rig config camera's `metric: true`):
  // its unit is the metre in every segment, its scale fixed to 1. A master segment change then
  // only breaks the keyframe pairs (no motion spans two master frames); the slaves' position
  // statistics and scales, in metres, are kept. Otherwise a new master segment is a new unit
  // and positions and scales restart.
  bool master_metric = false;

  // Models: purely translational (rotation + scale) while no formed motion rotates by the
  // equal-error boundary of thesis 5.2, else general or planar, as the batch calibrator decides
  // (model_selection_options.h). The boundary is the fixed alpha_maxrot_deg until
  // gate_after_motions motions have measured the rotation noise, and never below
  // pair_min_angle_deg.
  ModelSelectionOptions model_selection;
  // Hysteresis: once general (and after converged_min_motions motions), the estimate turns
  // planar again only when a figure is worse than its threshold by planar_hysteresis (SNR below
  // model_selection.min_tilt_snr / h or ratio above max_axis_std_ratio * h), so the model does
  // not flip from keyframe to keyframe.
  double planar_hysteresis = 2.0;

  // Convergence: enough motions, small uncertainty, stable over the last keyframes.
  int converged_min_motions = 30;
  double converged_rot_std_deg = 0.3;
  // of |C|, or of the median length of the master's motions when that is longer (cameras close
  // together: a fraction of |C| → 0 is never reached; a length in the master's own unit)
  double converged_pos_std_fraction = 0.05;
  int converged_stable_keyframes = 5;

  // Rotation σ, cluster-robust: the motions' rotation information is kept in contiguous time
  // blocks of sigma_block_s (at most sigma_blocks; when full, neighbours merge and blocks
  // last twice as long), errors shared within a block and independent between blocks. The
  // published rotation σ is at least that once sigma_min_blocks blocks exist (0 s = off:
  // independent motions with the overlap of the pairs counted).
  double sigma_block_s = 10.0;
  int sigma_blocks = 20;
  int sigma_min_blocks = 8;

  // Motions kept per slave for the background non-linear refinement window.
  int window_size = 400;

  // Pose history for the background refinement: at most history_sets sets are kept per slave
  // (about 140 bytes each), spanning the drive since the last restart (start, master
  // re-initialisation, decalibration): every set until the drive outgrows it, then the group
  // means of 2, 4, ... consecutive sets (each the mean in the group of rigid motions, which
  // keeps the rig's relation between the poses and, on white pose noise, the information of
  // every set). The background refinement is the batch
  // calibrator's on them (CalibrateRig: its pair choice, time-block σ), at most every
  // history_refine_period_s of stream time, so the online estimate ends where the batch one
  // does. After a resume (no poses before it) the refinement is the window refinement of the
  // statistics. 0 = off.
  int history_sets = 10000;
  double history_refine_period_s = 30.0;
  int history_min_sets = 50;  // fewer sets: the window refinement

  // Nominal extrinsics per slave (from the rig config), used for what the motion cannot
  // determine (the offset of C along the rotation axis of planar motion). Empty = none.
  std::vector<std::optional<Similarity>> nominal;
  // σ of the nominal C along the mean rotation axis (master units): > 0 combines it with the
  // estimate as a weighted term in the general model too; 0 = used only where unobservable.
  double nominal_sigma = 0.0;

  // The first violated constraint as "<field>: <constraint>".
  Status Check() const;
};

// The batch calibrator's options of the history refinement (RefinementJob::history_options,
// whose result is published): the online estimator's model selection, its smallest rotation of
// the general model (pair_min_angle_deg as alpha_threshold_deg) and nominal σ, so that the
// config's options decide the published model as they decide the online one.
CalibrationOptions HistoryCalibrationOptions(const RigEstimatorOptions& options);

}  // namespace rigcal
