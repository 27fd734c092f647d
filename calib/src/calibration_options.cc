// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/calibration_options.h"

#include <cmath>
#include <sstream>

namespace rigcal {

Status CalibrationOptions::Check() const {
  std::ostringstream e;
  if (const Status pair_status = pairs.Check(); !pair_status.ok())
    e << "pairs." << pair_status.message();
  else if (scale_model == ScaleModel::kPartitions && partitions < 1)
    e << "partitions: must be >= 1 for the partition scale model, got " << partitions;
  else if (alpha_threshold_deg < 0.0 || alpha_threshold_deg >= 180.0)
    e << "alpha_threshold_deg: must be in [0, 180), got " << alpha_threshold_deg;
  else if (const Status model = model_selection.Check(); !model.ok())
    e << model.message();
  else if (!(scale_deviation_threshold > 0.0))
    e << "scale_deviation_threshold: must be > 0, got " << scale_deviation_threshold;
  else if (min_motions_per_partition < 2)
    e << "min_motions_per_partition: must be >= 2, got " << min_motions_per_partition;
  else if (scale_dot_epsilon < 0.0)
    e << "scale_dot_epsilon: must be >= 0 (0 = automatic), got " << scale_dot_epsilon;
  else if (!(outlier_mad_factor > 0.0))
    e << "outlier_mad_factor: must be > 0, got " << outlier_mad_factor;
  else if (angle_invariant_floor_deg < 0.0)
    e << "angle_invariant_floor_deg: must be >= 0, got " << angle_invariant_floor_deg;
  else if (max_outlier_rounds < 0)
    e << "max_outlier_rounds: must be >= 0, got " << max_outlier_rounds;
  else if (!(robust_scale > 0.0))
    e << "robust_scale: must be > 0, got " << robust_scale;
  else if (covariance_time_blocks != 0 &&
           (covariance_time_blocks < 2 || covariance_time_blocks > 10000))
    e << "covariance_time_blocks: must be 0 (off) or in [2, 10000], got " << covariance_time_blocks;
  else if (max_iterations < 1)
    e << "max_iterations: must be >= 1, got " << max_iterations;
  else if (!(nominal_sigma >= 0.0) || std::isinf(nominal_sigma))
    e << "nominal_sigma: must be finite and >= 0 (0 = no weighted prior), got " << nominal_sigma;
  else if (min_motions < 2)
    e << "min_motions: must be >= 2, got " << min_motions;
  if (e.str().empty()) return Status::Ok();
  return Error{e.str()};
}

std::string ToString(Method m) { return m == Method::kLinear ? "lls" : "nl"; }

std::string ToString(MotionModel m) {
  switch (m) {
    case MotionModel::kAuto:
      return "auto";
    case MotionModel::kGeneral:
      return "general";
    case MotionModel::kTranslational:
      return "translational";
    case MotionModel::kPlanar:
      return "planar";
  }
  return "?";
}

std::string ToString(ScaleModel m) {
  switch (m) {
    case ScaleModel::kAuto:
      return "auto";
    case ScaleModel::kFixed:
      return "fixed";
    case ScaleModel::kSegments:
      return "segments";
    case ScaleModel::kPartitions:
      return "partitions";
  }
  return "?";
}

}  // namespace rigcal
