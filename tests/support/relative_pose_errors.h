// SPDX-License-Identifier: Apache-2.0
#pragma once
// Errors of an odometry's relative motions against a reference (AprilTag poses of a real
// sequence, a renderer's truth): for frame pairs (a, b), the rotation error of b's pose in a's
// frame, the angle between the two translation directions, and the scale (reference length /
// odometry length), which is constant within one scale segment of a perfect odometry.
// Poses are Pose{q, C} (camera orientation world_from_cam and centre) in any world frame of
// their own: only motions in the frame of camera a are compared.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::support {

struct RelativePoseError {
  int a = 0;
  int b = 0;
  double rotation_deg = 0.0;
  double direction_deg = 0.0;     // 0 when either translation is zero
  double scale = 0.0;             // reference length / estimate length (0: no estimate length)
  double reference_length = 0.0;  // length of the reference translation, its units
};

// The relative motion of b in a's frame of the estimate against the reference's.
RelativePoseError CompareRelativeMotion(const Pose& estimate_a, const Pose& estimate_b,
                                        const Pose& reference_a, const Pose& reference_b);

// For every frame a of `estimate` with a pose at b = a + step in the estimate and poses at a
// and b in `reference` (frame index -> pose).
std::vector<RelativePoseError> RelativePoseErrors(const std::map<int, Pose>& estimate,
                                                  const std::map<int, Pose>& reference, int step);

struct ErrorStats {
  int count = 0;
  double median = 0.0;
  double p90 = 0.0;
};
// Median and 90th percentile (nearest rank); zeros for no value.
ErrorStats Stats(std::vector<double> values);

// Scale consistency of one segment's pairs: the median of |scale / median scale - 1| over the
// pairs whose reference length is at least `min_reference_length` (0 when fewer than 2).
double ScaleSpread(const std::vector<RelativePoseError>& errors, double min_reference_length);

// "rotation median 0.41 p90 0.80 deg, direction median 9.1 p90 20.3 deg (n 89)".
std::string Describe(const std::vector<RelativePoseError>& errors);

}  // namespace rigcal::support
