// SPDX-License-Identifier: Apache-2.0
#pragma once
// Internal working form of a rig motion for the solvers.

#include <Eigen/Core>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::internal {

struct MotionData {
  Eigen::Vector4d q0;  // master rotation (w, x, y, z)
  Eigen::Vector4d qi;  // slave rotation, sign aligned with q0 (see AlignSigns)
  Eigen::Matrix3d R0;
  Eigen::Vector3d C0;
  Eigen::Vector3d Ci;
  double angle0 = 0.0;  // rotation angles, radians
  double anglei = 0.0;
  int scale_index = 0;  // which scale variable this motion's slave translation uses
  int segment = 0;
  int scale_key = 0;        // segment id or partition number behind scale_index
  int64_t t_ns = 0;         // mid-time of the motion
  int64_t duration_ns = 0;  // t_b - t_a
  int64_t t_a_ns = 0;       // times of its two poses (start, end)
  int64_t t_b_ns = 0;
};

std::vector<MotionData> ToMotionData(const std::vector<RigMotion>& motions);

// Makes the scalar parts of q0 and qi non-negative: for a consistent pair both then equal
// cos(angle / 2), which fixes the sign ambiguity of q and -q except near 180 degrees.
void AlignSignsCanonical(std::vector<MotionData>* motions);

// Chooses, per motion, the sign of qi that best satisfies q0 · dq = dq · qi for the given dq.
// Resolves the motions near 180 degrees that canonical alignment can get wrong.
void AlignSignsWith(const Eigen::Vector4d& dq, std::vector<MotionData>* motions);

}  // namespace rigcal::internal
