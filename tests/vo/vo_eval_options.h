// SPDX-License-Identifier: Apache-2.0
#pragma once
// VoOptions for the VO evaluations, with the overrides of RIGCAL_VO_EVAL_OPTIONS
// ("field=value,field=value"; integer and floating-point fields by name), to measure what an
// option changes without rebuilding. An unknown field fails the test.

#include <gtest/gtest.h>

#include <cstdlib>
#include <map>
#include <string>

#include "rigcal/vo/monocular_vo.h"

namespace rigcal::vo {

inline VoOptions EvalOptions() {
  VoOptions o;
  const char* text = std::getenv("RIGCAL_VO_EVAL_OPTIONS");
  if (text == nullptr) return o;
  const std::map<std::string, int*> ints = {
      {"grid_cell_px", &o.grid_cell_px},
      {"max_features", &o.max_features},
      {"fast_threshold", &o.fast_threshold},
      {"klt_window_px", &o.klt_window_px},
      {"klt_pyramid_levels", &o.klt_pyramid_levels},
      {"ba_window", &o.ba_window},
      {"ba_max_iterations", &o.ba_max_iterations},
      {"keyframe_max_frames", &o.keyframe_max_frames},
      {"min_tracking_inliers", &o.min_tracking_inliers},
      {"min_init_inliers", &o.min_init_inliers},
      {"min_init_tracks", &o.min_init_tracks},
      {"noise_window_frames", &o.noise_window_frames},
      {"relocalisation_min_inliers", &o.relocalisation_min_inliers},
      {"affine_half_size", &o.affine_half_size}};
  const std::map<std::string, uint32_t*> unsigned_ints = {{"seed", &o.seed}};
  const std::map<std::string, double*> doubles = {
      {"klt_max_fb_error_px", &o.klt_max_fb_error_px},
      {"inlier_sigmas", &o.inlier_sigmas},
      {"noise_floor_px", &o.noise_floor_px},
      {"init_depth_precision", &o.init_depth_precision},
      {"min_init_parallax_deg", &o.min_init_parallax_deg},
      {"keyframe_parallax_deg", &o.keyframe_parallax_deg},
      {"keyframe_track_ratio", &o.keyframe_track_ratio},
      {"min_triangulation_angle_deg", &o.min_triangulation_angle_deg},
      {"min_inlier_ratio", &o.min_inlier_ratio},
      {"relocalisation_timeout_s", &o.relocalisation_timeout_s},
      {"huber_sigmas", &o.huber_sigmas},
      {"affine_max_shift_px", &o.affine_max_shift_px},
      {"affine_min_area", &o.affine_min_area},
      {"affine_max_area", &o.affine_max_area},
      {"normal_fov_sr", &o.normal_fov_sr}};
  std::string all(text);
  size_t start = 0;
  while (start < all.size()) {
    const size_t end = std::min(all.find(',', start), all.size());
    const std::string item = all.substr(start, end - start);
    const size_t eq = item.find('=');
    if (eq != std::string::npos) {
      const std::string key = item.substr(0, eq), value = item.substr(eq + 1);
      if (ints.count(key)) *ints.at(key) = std::stoi(value);
      if (unsigned_ints.count(key))
        *unsigned_ints.at(key) = static_cast<uint32_t>(std::stoul(value));
      if (doubles.count(key)) *doubles.at(key) = std::stod(value);
      if (!ints.count(key) && !doubles.count(key) && !unsigned_ints.count(key)) {
        ADD_FAILURE() << "unknown option " << key;
      }
    }
    start = end + 1;
  }
  return o;
}

}  // namespace rigcal::vo
