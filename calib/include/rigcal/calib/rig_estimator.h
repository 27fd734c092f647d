#pragma once
// RigEstimator: the recursive, bounded-memory online counterpart of the batch calibrator.
//
// Feed it time-corresponding sets of camera poses (master + slaves, from the SyncBuffer); it
// picks keyframes, forms motion pairs between keyframes, gates them with the scale-free
// invariants, and accumulates fixed-size sufficient statistics per slave whose linear
// solution equals the batch linear least squares of the same motions. Closed odometry scale
// segments are marginalised, old information is forgotten exponentially, and a short-window
// twin of the statistics detects a camera that moved (decalibration).
//
// Not thread-safe: one estimator thread owns it (see OnlineCalibrator for the threads).

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/estimator_state.h"
#include "rigcal/base/status.h"
#include "rigcal/base/types.h"

namespace rigcal {
namespace internal {
class PoseGlitchGate;
}

struct RigEstimatorOptions {
  // Keyframes (per slave): a set becomes a keyframe when the master has rotated by
  // keyframe_min_angle_deg or moved by keyframe_min_translation (master units) since the last
  // keyframe, or keyframe_max_interval_ns has passed.
  double keyframe_min_angle_deg = 2.0;
  double keyframe_min_translation = 0.05;
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

  // Models.
  // Purely translational (rotation + scale) while no motion rotates by the equal-error
  // boundary of thesis 5.2, as CalibrationOptions: alpha_maxrot_deg at an orientation noise of
  // alpha_maxrot_noise_deg, scaled by sqrt(eps / alpha_maxrot_noise_deg) for the running
  // rotation noise eps of the motions (RMS of the master-minus-slave rotation angle
  // differences), never below pair_min_angle_deg; the fixed alpha_maxrot_deg until
  // gate_after_motions motions have measured eps, or when alpha_maxrot_noise_deg = 0.
  double alpha_maxrot_deg = 10.0;
  double alpha_maxrot_noise_deg = 1.0;
  // General or planar, as CalibrationOptions (the same figures): the general model needs the
  // rotation axes to tilt by min_tilt_snr times the noise (or to spread by
  // general_axis_spread_deg) and the σ of C along the mean axis within max_axis_std_ratio
  // times its in-plane σ. Hysteresis: once general (and after converged_min_motions
  // motions), the estimate turns planar again only when a figure is worse than its threshold
  // by planar_hysteresis (SNR below min_tilt_snr / h or ratio above max_axis_std_ratio * h),
  // so the model does not flip from keyframe to keyframe. Master axes whose spread is below
  // planar_axis_spread_deg count as one axis whatever the figures (0 = off).
  double min_tilt_snr = 10.0;
  double max_axis_std_ratio = 100.0;
  double general_axis_spread_deg = 10.0;  // axes spread this much: general, whatever the SNR
  double planar_hysteresis = 2.0;
  double planar_axis_spread_deg = 0.0;

  // Convergence: enough motions, small uncertainty, stable over the last keyframes.
  int converged_min_motions = 30;
  double converged_rot_std_deg = 0.3;
  double converged_pos_std_fraction = 0.05;  // of |C|, or absolute when |C| < 1
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

  // Pose history for the background refinement: the poses of the last history_sets sets are
  // kept per slave (about 130 bytes each). While they hold every set since the last restart
  // (start, master re-initialisation, decalibration), the background refinement is the batch
  // calibrator's on them (CalibrateRig: its pair choice, time-block σ), at most every
  // history_refine_period_s of stream time, so the online estimate ends where the batch one
  // does. Once the history has dropped sets (a longer recording), the refinement is the window
  // refinement of the statistics. 0 = off.
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

struct SlaveOnlineState {
  uint32_t flags = 0;  // SlaveFlags (slave_state.h)
  int segment = 0;                  // current odometry segment of the slave
  int64_t last_update_ns = 0;       // stream time of the last accepted motion
  double short_long_rot_deg = 0.0;  // disagreement of the short and long windows
  int keyframes = 0;
  int gated_scale = 0;  // rejected by the screw-pitch scale gate
  int decalibration_events = 0;
  // Cameras that run free (OnlineOptions::time_offset; set by OnlineCalibrator::Estimate): the
  // clock offset is estimated from the data (else given), it is known (usable), the clock drift
  // dτ/dt in ppm, and the jumps of the offset detected (a camera restarted).
  bool clock_offset_estimated = false;
  bool clock_offset_known = false;
  double clock_drift_ppm = 0.0;
  double clock_drift_std_ppm = std::numeric_limits<double>::quiet_NaN();  // NaN: unknown
  int clock_jumps = 0;
};

struct RigEstimate {
  int64_t t_ns = 0;            // stream time of the last set
  uint64_t sets = 0;           // sets consumed
  uint64_t rejected_sets = 0;  // sets ignored: time not increasing, no or non-finite master
  RigCalibration rig;          // per slave: the result in the batch schema
  std::vector<SlaveOnlineState> online;  // per slave
  // Cameras that run free: restarts of the master's clock followed (SyncBuffer::ClockJumps(0);
  // OnlineCalibrator). A slave's online.clock_jumps counts its own clock's.
  int master_clock_jumps = 0;
};

// Everything the statistics know about the motions that are NOT in the refinement window,
// as the exact sums of squared linear residuals of those motions (the residuals the
// refinement minimises, thesis 4.26):
//   sum w |A q|^2 = q^T rotation q                                                  (4.10)
//   sum w |(I - R0) C + λ_s dR C_i - C0|^2 = u^T position u,  u = [C; λ_1 vec(dR); ...; 1]
// with one 9-block per entry of `segments` (the open scale segments, vec column-major).
// Closed segments enter through their Schur complement on C (marginalised at the rotation of
// the time). A window refinement with this prior minimises over every motion since the start
// (or the last reset), not only the window's: the window adds nothing but robust re-weighting.
struct RefinementPrior {
  double weight = 0.0;  // sum of the motions' weights (0: no prior)
  int motions = 0;      // how many motions
  Eigen::Matrix4d rotation = Eigen::Matrix4d::Zero();
  std::vector<int> segments;
  Eigen::MatrixXd position;  // (4 + 9 * segments.size()) square, positive semi-definite
};

// One slave's refinement job: a copy of the window and the linear estimate to start from.
struct RefinementJob {
  int slave = 0;
  std::vector<RigMotion> motions;
  // Per motion: how much of it the statistics still hold (exponential forgetting since it was
  // added, in (0, 1]). Its residuals are weighted by it; the robust loss replaces the Huber
  // weights of the statistics.
  std::vector<double> weights;
  SlaveCalibration start;
  uint64_t generation = 0;  // estimator generation when the job was made
  // Prior on C along start.observability.planar_axis (from the nominal mounting, when
  // options.nominal_sigma > 0): the general model adds it as a weighted term. The planar model
  // keeps C along the axis at start's value (the nominal's or 0) in any case.
  double axis_prior = 0.0;
  double axis_prior_sigma = 0.0;
  // The motions accumulated before the window (see RefinementPrior).
  RefinementPrior prior;
  // Huber loss (at 3 sigma) on the window's residuals; the prior has none.
  bool robust_loss = true;
  // Every set since the last restart (master and this slave, slaves[0], then every other slave
  // whose history holds those sets), when the pose history holds them and a history refinement
  // is due: RefineWindow then runs the batch calibrator on it with `history_options` instead of
  // refining the window, and solves this slave (the others' poses tell glitches apart, as in
  // the batch on the whole recording).
  RigRecording history;
  CalibrationOptions history_options;
  // Stream time of the newest set in `history` (when the refinement was made).
  int64_t history_t_ns = 0;
};

class RigEstimator {
 public:
  // camera_names[0] is the master. Throws InvalidOptions when options.Check() fails.
  RigEstimator(std::vector<std::string> camera_names, RigEstimatorOptions options);
  ~RigEstimator();
  RigEstimator(const RigEstimator&) = delete;
  RigEstimator& operator=(const RigEstimator&) = delete;

  // Consumes one time-corresponding set: poses[0] master, poses[i] slave i (nullopt when the
  // slave is missing from this set). Sets must come in increasing time. Non-finite poses are
  // counted as rejected and ignored; glitched poses (a jump, a rotated pose: pose_glitch_gate)
  // are skipped and counted in the slave's `glitches`.
  void AddSet(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses);

  // The current estimate of every slave (cheap: cached at each accepted motion).
  const RigEstimate& Estimate() const;

  // Background refinement support: a copy of a slave's window, and the outcome to publish
  // when it is consistent with the current linear estimate (within gate_sigmas).
  // `final`: a history refinement even when not due (the end of a stream).
  RefinementJob MakeRefinementJob(int slave, bool final = false) const;
  bool ApplyRefinement(const RefinementJob& job, const SlaveCalibration& refined);

  // The statistics of every slave, to continue after a restart (estimator_state.h; the file
  // format is tools/io's estimator_state_file.h).
  RigEstimatorState SaveState() const;
  // Continues from a saved state: the refinement window starts empty (every saved motion is in
  // its prior) and the estimate is re-solved. A state of other cameras (names, count) or with
  // another number of slaves is rejected with a message, and the estimator is left unchanged.
  Status RestoreState(const RigEstimatorState& state);

 private:
  struct Slave;
  // The stages of one slave's update (calib/src/: keyframe_pairing, motion_gates,
  // statistics_accumulation), then Publish.
  void UpdateSlave(int index, int64_t t_ns, const CameraPose& master, const CameraPose& slave);
  // Solves and publishes a slave's estimate (statistics_solution, decalibration_check,
  // window_refinement, online_uncertainty, convergence_check, model_explanation).
  void Publish(int index);
  void PublishCounts(int index);
  // The nominal mounting of slave `index`, when the options give one.
  std::optional<Similarity> NominalOf(int index) const;

  std::vector<std::string> names_;
  RigEstimatorOptions options_;
  std::vector<std::unique_ptr<Slave>> slaves_;
  std::unique_ptr<internal::PoseGlitchGate> glitch_gate_;  // pose_glitch_gate
  RigEstimate estimate_;
  int master_segment_ = 0;
  bool have_master_segment_ = false;
  uint64_t generation_ = 0;
  std::vector<int64_t> consumed_t_ns_;  // RigEstimatorState::consumed_t_ns, per camera
};

// Runs the non-linear refinement (thesis 4.26/4.27 with Ceres) of a job. Pure function:
// safe to call from a background thread on a copied job.
SlaveCalibration RefineWindow(const RefinementJob& job);

}  // namespace rigcal
