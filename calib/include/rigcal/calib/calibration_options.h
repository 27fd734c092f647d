#pragma once
// Options of the batch rig calibrator: plain struct, documented defaults, Check().

#include <string>

#include "rigcal/calib/pair_selection.h"

namespace rigcal {

enum class Method { kLinear, kNonlinear };
enum class MotionModel { kAuto, kGeneral, kTranslational };
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
  // Purely translational model when every motion rotates less than this (thesis 5.2).
  double alpha_maxrot_deg = 10.0;
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

  // Planar motion: rotation axes whose spread (sqrt of the second eigenvalue of the
  // axis scatter) is below this angle count as one axis.
  double planar_axis_spread_deg = 1.0;

  // Needs at least this many usable motions per slave.
  int min_motions = 2;

  bool Check(std::string* error) const;
};

std::string ToString(Method m);
std::string ToString(MotionModel m);
std::string ToString(ScaleModel m);

}  // namespace rigcal
