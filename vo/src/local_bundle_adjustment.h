// SPDX-License-Identifier: Apache-2.0
#pragma once
// Windowed bundle adjustment of the VO map with Ceres: keyframe poses and landmark positions
// minimise the Huber-robust chord distance between observed unit bearings and the directions
// to the landmarks (angular residuals, valid on the whole sphere).

#include <vector>

#include "vo_map.h"

namespace rigcal::vo {

struct LocalBaOptions {
  // The first `num_fixed` keyframes of the window are held constant (gauge; with 2 the scale
  // is fixed too).
  int num_fixed = 2;
  // Two-view initialisation: the keyframe after the fixed one keeps its centre on the unit
  // sphere (||C|| = 1, thesis scale convention); needs num_fixed = 1 and the first keyframe
  // at the origin.
  bool unit_baseline = false;
  int max_iterations = 10;
  double huber_rad = 2e-3;
  // After the solve, observations with an angular error above this are removed, and so are
  // the landmarks left with fewer than two observations.
  double outlier_rad = 6e-3;
};

struct LocalBaSummary {
  bool success = false;
  int num_keyframes = 0;
  int num_landmarks = 0;
  int num_residuals = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  int removed_observations = 0;
  int removed_landmarks = 0;
};

// Adjusts the keyframes `window` (ids, oldest first) and every landmark with at least two
// observations in them. `map` must not be null.
LocalBaSummary LocalBundleAdjust(const std::vector<int>& window, const LocalBaOptions& options,
                                 VoMap* map);

}  // namespace rigcal::vo
