// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pair-policy evaluation (`rigcal experiment pairs`): on a wide set of recordings — white
// pose noise (motion capture, PnP), drifting VO-like noise, hand-held 6-DoF, car drives, slow
// and fast rotation, 10-100 Hz, short and long — the error of the default pair policy against
// every fixed span `relative:N`, and of the online estimator against the batch solve.
// Every policy of a scenario is solved on the same noisy recordings (paired comparison); the
// figures are RMS over `repeats` noise draws, so the best fixed span is not the luck of one draw.

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/research/experiments.h"

namespace rigcal::research {

// Pose errors of one camera's odometry. White: independent per pose (motion capture, PnP).
// Drift: every relative motion between consecutive poses is perturbed and the poses are their
// composition (visual odometry): rotation by drift_rot_deg per frame, translation by
// drift_trans_fraction of its length per component.
struct PoseNoiseModel {
  std::string name;
  double white_rot_deg = 0.0;
  double white_pos = 0.0;  // master units (metres for the real trajectories); slaves: scaled
  double drift_rot_deg = 0.0;
  double drift_trans_fraction = 0.0;
};

struct PairScenario {
  std::string name;                // e.g. "kitti00-10Hz-vo"
  std::string source;              // where the master trajectory comes from
  SampledTrajectory master;        // true world_from_master
  std::vector<std::string> names;  // master then slaves
  std::vector<Similarity> rig;     // true rig per slave
  PoseNoiseModel noise;
  // A drive on a level road: C along the rotation axis is not determined by any pairs, so
  // position errors are compared across the axis (the estimate's mean rotation axis).
  bool planar = false;
};

// The evaluation set: simulated drives (6-DoF slow and fast, car, 10-100 Hz, short and long)
// and, when `trajectory_dir` holds them, the real KITTI 00 and EuRoC V1_02 ground truths
// (KITTI_00_gt.txt + KITTI_00_gt_times.txt, V102_groundtruth.csv), each with white, drifting and
// mixed noise. Trajectories not found are listed in *notes.
std::vector<PairScenario> PairScenarios(const std::string& trajectory_dir,
                                        std::vector<std::string>* notes);

// Recordings none of the above are like, to check that online matches the batch on rigs it was
// not tuned for: a four-camera rig (a camera looking up, one down and back, one on a long
// boom; odometry scales 0.1, 4 and 1.3) on simulated 6-DoF drives at 5 Hz for 600 s and 50 Hz
// for 40 s, EuRoC V1_02 at 40 Hz and the first 200 s of KITTI 00 at 5 Hz, with white noise of
// two levels and pure drift.
std::vector<PairScenario> HeldOutPairScenarios(const std::string& trajectory_dir,
                                               std::vector<std::string>* notes);

// `exact` made noisy by `noise`; `unit` = master units per unit of this camera's odometry
// (white position noise is in master units).
CameraTrack AddPoseNoise(const CameraTrack& exact, const PoseNoiseModel& noise, double unit,
                         std::mt19937_64& rng);

// One noisy recording of `scenario` (the draw `seed`): the exact drive along its master, then
// each camera's odometry errors.
RigRecording NoisyRecording(const PairScenario& scenario, uint64_t seed);

struct PairEvaluationOptions {
  int repeats = 3;  // noise draws per scenario
  uint64_t seed = 1;
  int threads = 2;  // 0 = all cores; results do not depend on it
  std::vector<int> spans = {1, 2, 5, 10, 20, 50, 100, 200, 400};  // fixed spans compared
  bool online = true;              // also replay through the online estimator
  int online_history_sets = -1;    // its pose history (RigEstimatorOptions); -1 = the default
  bool gls = true;                 // also the gls pair policy
  std::string only;                // run the scenarios whose name contains this
  CalibrationOptions calibration;  // everything but the pairs
  ExperimentProgress progress;     // optional, one unit = one scenario draw
};

// RMS over the draws and slaves of one policy's errors, and of its reported σ.
struct PolicyFigures {
  std::string policy;  // "auto", "relative:N", "online"
  int span = 0;        // N of relative:N, 0 otherwise
  int results = 0;     // slave results with an estimate
  int failed = 0;      // slave results without an estimate
  double rot_rms_deg = kNotAvailable;
  double pos_rms = kNotAvailable;  // |C - C_hat|, master units (across the axis when planar)
  double scale_rms_pct = kNotAvailable;
  double rot_sigma_rms_deg = kNotAvailable;  // RMS of the reported rotation σ
  double pos_sigma_rms = kNotAvailable;      // RMS of |σ_C|
  // RMS of the normalised errors: rotation angle / (√3 largest-axis σ), |ΔC| / |σ_C|.
  double rot_z_rms = kNotAvailable;
  double pos_z_rms = kNotAvailable;
  std::string chosen;  // auto: the pairs it chose, per slave and draw (first few)
};

struct PairScenarioResult {
  std::string name;
  std::string source;
  std::string noise;
  int poses = 0;
  double rate_hz = 0.0;
  double duration_s = 0.0;
  std::vector<PolicyFigures> policies;  // auto, relative:N..., online (when run)
  // The fixed span with the smallest rotation / position RMS (index into policies).
  int best_rot = -1;
  int best_pos = -1;
  // The best fixed span's error without the luck of the draws: the span best on the even draws
  // judged on the odd ones and vice versa (RMS of the two). The minimum over spans of errors
  // measured on the same draws is biased low by their noise; this reference is not. NaN with
  // fewer than 2 repeats.
  double cv_rot_rms_deg = kNotAvailable;
  double cv_pos_rms = kNotAvailable;
  const PolicyFigures* Find(const std::string& policy) const;
};

std::vector<PairScenarioResult> RunPairEvaluation(const std::vector<PairScenario>& scenarios,
                                                  const PairEvaluationOptions& options);

// The table: per scenario the best fixed span's rotation and position RMS, auto's and its
// ratio to them, online's ratio to auto (batch); then how many scenarios meet 1.2x / 1.5x.
std::string FormatPairTable(const std::vector<PairScenarioResult>& results);
// Every policy of every scenario, one CSV row each.
std::string PairCsv(const std::vector<PairScenarioResult>& results);

}  // namespace rigcal::research
