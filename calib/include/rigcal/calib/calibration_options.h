// SPDX-License-Identifier: Apache-2.0
#pragma once
// Options of the batch rig calibrator: plain struct, documented defaults, Check().

#include <atomic>
#include <map>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/model_selection_options.h"
#include "rigcal/calib/pair_options.h"

namespace rigcal {

enum class Method { kLinear, kNonlinear };
// kGeneral: the thesis's general model (4.3); kPlanar: every rotation about one axis (a car on
// a road): rotation, scale and in-plane position, the offset along the axis unobservable;
// kTranslational: no rotation (4.5).
enum class MotionModel { kAuto, kGeneral, kTranslational, kPlanar };
enum class ScaleModel {
  kAuto,        // segments if the data has several, partitions when measured scales drift
  kFixed,       // one scale per slave (thesis time-fixed model)
  kSegments,    // one scale per scale segment id of the slave
  kPartitions,  // `partitions` equal parts of the motions (thesis SetScalesPerCamera(n))
};
enum class RobustLoss { kNone, kHuber, kCauchy };

struct CalibrationOptions {
  Method method = Method::kNonlinear;
  MotionModel motion_model = MotionModel::kAuto;
  ScaleModel scale_model = ScaleModel::kAuto;
  int partitions = 1;  // for kPartitions (and the partition count kAuto may pick up to)

  PairOptions pairs;

  // Motions whose master rotation is below this angle are not used by the general model
  // (thesis alpha_threshold, 4.3.1).
  double alpha_threshold_deg = 2.0;
  // The motion-model decision (motion_model kAuto): purely translational below the
  // equal-error boundary, else general or planar (model_selection_options.h). The general
  // model, forced (kGeneral), reports planar motion (axes that do not tilt by these figures)
  // as degenerate.
  ModelSelectionOptions model_selection;
  // Time-dependent scales when measured scales deviate by more than this fraction (5.5).
  double scale_deviation_threshold = 0.03;
  // Auto partition count: each partition keeps at least this many motions.
  int min_motions_per_partition = 20;
  // Expected absolute error of the products C^T r in eq. (4.18); delta = 3 eps (4.23).
  // 0 = automatic: 1e-3 of the RMS slave translation length.
  double scale_dot_epsilon = 0.0;

  // Misfit removal: a motion is removed when the rotation angles of master and slave differ
  // (the scale-free invariant) or its residual is an outlier, both by more than
  // outlier_mad_factor robust standard deviations (1.4826 MAD), at least the floors below.
  double outlier_mad_factor = 5.0;
  double angle_invariant_floor_deg = 0.05;
  int max_outlier_rounds = 3;

  // Non-linear refinement (4.26-4.27).
  RobustLoss robust_loss = RobustLoss::kNone;
  double robust_scale = 3.0;  // in units of the whitened residual (standard deviations)
  int max_iterations = 100;
  bool compute_covariance = true;
  // The covariance of independent motions is optimistic when motions close in time share
  // their errors (overlapping pairs, correlated pose errors, drift): the reported σ are at
  // least the cluster-robust (sandwich) ones with the motions cut into this many contiguous
  // time blocks, errors independent between blocks only (needs 4 motions per block; 0 = off).
  int covariance_time_blocks = 20;

  // Nominal mounting per slave name (CAD, a rig config's cameras[].nominal), master frame.
  // Used for what the motions do not determine: C along the rotation axis of planar motion.
  std::map<std::string, Similarity> nominal;
  // σ of the nominal C along the mean rotation axis, master units. > 0: a weighted term
  // (C·a - C_nominal·a) / σ in the refinement, in the general model too; 0: the nominal value
  // is used only where the motion determines nothing.
  double nominal_sigma = 0.0;

  // Needs at least this many usable motions per slave.
  int min_motions = 2;

  // Set by another thread to end the solve early (a periodic refinement in flight when the run
  // is stopped by a signal): the stages check it between their steps, the noise fit between its
  // components and the non-linear solver at every iteration. A cancelled solve returns a result
  // that is not solved (Termination::kCancelled), only to be dropped. Null: never cancelled.
  const std::atomic<bool>* cancel = nullptr;
  bool cancelled() const { return cancel != nullptr && cancel->load(std::memory_order_relaxed); }

  // The first violated constraint as "<field>: <constraint>" (pairs: PairOptions's message;
  // model_selection: ModelSelectionOptions's).
  Status Check() const;
};

std::string ToString(Method m);
std::string ToString(MotionModel m);
std::string ToString(ScaleModel m);

}  // namespace rigcal
