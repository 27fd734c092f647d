// SPDX-License-Identifier: Apache-2.0
// VoOptions::Check and the names of the VO states.

#include <cmath>
#include <utility>

#include "rigcal/vo/monocular_vo.h"

namespace rigcal::vo {

Status VoOptions::Check() const {
  // The first violated constraint, in the order of the fields.
  const std::pair<bool, const char*> rules[] = {
      {grid_cell_px >= 4, "grid_cell_px: must be >= 4"},
      {max_features >= 20, "max_features: must be >= 20"},
      {normal_fov_sr >= 0.0 && normal_fov_sr <= 4.0 * M_PI,
       "normal_fov_sr: must be in [0, 4 pi] (0: max_features for every lens)"},
      {fast_threshold >= 1 && fast_threshold <= 255, "fast_threshold: must be in [1, 255]"},
      {klt_window_px >= 5 && klt_window_px % 2 == 1, "klt_window_px: must be odd and >= 5"},
      {klt_pyramid_levels >= 0 && klt_pyramid_levels <= 8, "klt_pyramid_levels: must be in [0, 8]"},
      {klt_max_fb_error_px > 0.0, "klt_max_fb_error_px: must be > 0"},
      {border_px >= 0, "border_px: must be >= 0"},
      {affine_half_size >= 0 && affine_half_size <= 15, "affine_half_size: must be in [0, 15]"},
      {affine_max_shift_px > 0.0, "affine_max_shift_px: must be > 0"},
      {affine_min_area > 0.0 && affine_min_area < 1.0, "affine_min_area: must be in (0, 1)"},
      {affine_max_area > 1.0, "affine_max_area: must be > 1"},
      {inlier_sigmas > 0.0, "inlier_sigmas: must be > 0"},
      {huber_sigmas > 0.0, "huber_sigmas: must be > 0"},
      {noise_floor_px > 0.0, "noise_floor_px: must be > 0"},
      {noise_window_frames >= 1, "noise_window_frames: must be >= 1"},
      {ransac_max_iterations >= 1, "ransac_max_iterations: must be >= 1"},
      {ransac_confidence > 0.0 && ransac_confidence < 1.0, "ransac_confidence: must be in (0, 1)"},
      {min_init_tracks >= 8, "min_init_tracks: must be >= 8"},
      {min_init_inliers >= 8, "min_init_inliers: must be >= 8"},
      {init_depth_precision > 0.0 && init_depth_precision < 1.0,
       "init_depth_precision: must be in (0, 1)"},
      {min_init_parallax_deg >= 0.0, "min_init_parallax_deg: must be >= 0"},
      {min_init_cheirality_fraction > 0.0 && min_init_cheirality_fraction <= 1.0,
       "min_init_cheirality_fraction: must be in (0, 1]"},
      {min_tracking_inliers >= 4, "min_tracking_inliers: must be >= 4"},
      {min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0, "min_inlier_ratio: must be in [0, 1]"},
      {min_triangulation_angle_deg > 0.0, "min_triangulation_angle_deg: must be > 0"},
      {relocalisation_timeout_s >= 0.0, "relocalisation_timeout_s: must be >= 0"},
      {relocalisation_features >= 50, "relocalisation_features: must be >= 50"},
      {relocalisation_max_bits >= 1 && relocalisation_max_bits <= 256,
       "relocalisation_max_bits: must be in [1, 256]"},
      {relocalisation_ratio > 0.0 && relocalisation_ratio <= 1.0,
       "relocalisation_ratio: must be in (0, 1]"},
      {relocalisation_min_inliers >= 4, "relocalisation_min_inliers: must be >= 4"},
      {keyframe_track_ratio > 0.0 && keyframe_track_ratio <= 1.0,
       "keyframe_track_ratio: must be in (0, 1]"},
      {keyframe_parallax_deg > 0.0, "keyframe_parallax_deg: must be > 0"},
      {keyframe_max_frames >= 1, "keyframe_max_frames: must be >= 1"},
      {ba_window >= 3, "ba_window: must be >= 3"},
      {ba_max_iterations >= 0, "ba_max_iterations: must be >= 0"},
  };
  for (const auto& [ok, message] : rules) {
    if (!ok) return Error{message};
  }
  return Status::Ok();
}

std::string ToString(VoState state) {
  switch (state) {
    case VoState::kInitialising:
      return "initialising";
    case VoState::kTracking:
      return "tracking";
    case VoState::kLost:
      return "lost";
  }
  return "unknown";
}

}  // namespace rigcal::vo
