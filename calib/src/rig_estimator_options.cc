// SPDX-License-Identifier: Apache-2.0
// Check() of the recursive estimator's options.
#include "rigcal/calib/rig_estimator_options.h"

#include <cmath>
#include <sstream>

namespace rigcal {

Status RigEstimatorOptions::Check() const {
  std::ostringstream e;
  if (!(keyframe_min_angle_deg >= 0.0))
    e << "keyframe_min_angle_deg: must be >= 0";
  else if (!(keyframe_min_travel_s >= 0.0 && keyframe_min_travel_s <= 3600.0))
    e << "keyframe_min_travel_s: must be in [0, 3600] s";
  else if (keyframe_max_interval_ns <= 0)
    e << "keyframe_max_interval_ns: must be > 0";
  else if (keyframe_history < 2)
    e << "keyframe_history: must be >= 2, got " << keyframe_history;
  else if (!(pair_target_angle_deg > 0.0))
    e << "pair_target_angle_deg: must be > 0";
  else if (!(pair_target_translation_fraction > 0.0))
    e << "pair_target_translation_fraction: must be > 0";
  else if (pair_max_span_ns <= 0)
    e << "pair_max_span_ns: must be > 0";
  else if (!(angle_gate_floor_deg > 0.0))
    e << "angle_gate_floor_deg: must be > 0";
  else if (!(gate_sigmas > 0.0))
    e << "gate_sigmas: must be > 0";
  else if (!(huber_sigmas > 0.0))
    e << "huber_sigmas: must be > 0";
  else if (!(scale_gate > 0.0))
    e << "scale_gate: must be > 0";
  else if (half_life_s < 0.0)
    e << "half_life_s: must be >= 0 (0 = never forget)";
  else if (!(short_half_life_s > 0.0))
    e << "short_half_life_s: must be > 0";
  else if (decalibration_confirmations < 1)
    e << "decalibration_confirmations: must be >= 1";
  else if (!(decalibration_confirm_s >= 0.0 && decalibration_confirm_s <= 86400.0))
    e << "decalibration_confirm_s: must be in [0, 86400] seconds";
  else if (max_open_segments < 1)
    e << "max_open_segments: must be >= 1";
  else if (const Status model = model_selection.Check(); !model.ok())
    e << model.message();
  else if (window_size < 2)
    e << "window_size: must be >= 2";
  else if (history_sets < 0)
    e << "history_sets: must be >= 0 (0 = off)";
  else if (!(history_refine_period_s >= 0.0))
    e << "history_refine_period_s: must be >= 0";
  else if (history_min_sets < 2)
    e << "history_min_sets: must be >= 2";
  else if (converged_min_motions < 2)
    e << "converged_min_motions: must be >= 2";
  else if (!(planar_hysteresis >= 1.0))
    e << "planar_hysteresis: must be >= 1 (1 = none)";
  else if (!(nominal_sigma >= 0.0) || std::isinf(nominal_sigma))
    e << "nominal_sigma: must be finite and >= 0 (0 = no weighted prior)";
  else if (!(sigma_block_s >= 0.0) || std::isinf(sigma_block_s))
    e << "sigma_block_s: must be finite and >= 0 (0 = off), got " << sigma_block_s;
  else if (sigma_blocks < 4 || sigma_blocks > 1000)
    e << "sigma_blocks: must be in [4, 1000], got " << sigma_blocks;
  else if (sigma_min_blocks < 2 || sigma_min_blocks > sigma_blocks)
    e << "sigma_min_blocks: must be in [2, sigma_blocks], got " << sigma_min_blocks;
  if (e.str().empty()) return Status::Ok();
  return Error{e.str()};
}

CalibrationOptions HistoryCalibrationOptions(const RigEstimatorOptions& options) {
  CalibrationOptions history;
  history.model_selection = options.model_selection;
  history.alpha_threshold_deg = options.pair_min_angle_deg;
  history.nominal_sigma = options.nominal_sigma;
  return history;
}

}  // namespace rigcal
