// SPDX-License-Identifier: Apache-2.0
#pragma once
// Poses of a camera that runs free (calib: shared by `rigcal solve` and the online SyncBuffer) (its
// own capture instants, its own clock) at the master's instants, never across a gap of more than a
// few of the camera's frame intervals and never across a scale segment boundary: cubic (Lagrange
// through the two poses on either side, the rotation as rotation vectors in the tangent space of
// the pose before the instant) when the poses on both sides are there, else SLERP of the rotation
// and linear interpolation of the centre between the two poses around it. SLERP/linear alone err by
// a·dt²/8 (a the angular or linear acceleration), a bias that shrinks the motion and shifts the
// estimated centre by several σ on brisk drives; the cubic error is O(dt⁴).

#include <cstdint>
#include <optional>
#include <vector>

#include "rigcal/calib/timed_trajectory.h"

namespace rigcal {

// Median difference of consecutive stamps (0 with fewer than 2 stamps).
int64_t MedianInterval(const std::vector<int64_t>& t_ns);

// Pose of `trajectory` at `t_ns` (the trajectory's own clock) and its segment; nullopt
// outside its time range, across a gap or a segment boundary. `max_gap_ns` as above.
struct InterpolatedPose {
  Pose pose;
  int segment = 0;
};
std::optional<InterpolatedPose> InterpolatePose(const TimedTrajectory& trajectory, int64_t t_ns,
                                                int64_t max_gap_ns);

// The interpolation itself, without allocation (the SyncBuffer's, under its lock): the pose at
// `t_ns` from `count` consecutive poses `poses` stamped `t` (strictly increasing). count 2: the
// poses on either side of t_ns, SLERP and linear; count 4: two on either side, cubic. The
// caller checks gaps and segments.
Pose InterpolateAround(const int64_t* t, const Pose* poses, int count, int64_t t_ns);

}  // namespace rigcal
