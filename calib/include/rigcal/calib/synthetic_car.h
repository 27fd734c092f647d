// SPDX-License-Identifier: Apache-2.0
#pragma once
// Synthetic ground vehicle for the planar-motion tests and experiments: a four-camera car rig,
// car-like master trajectories (a level road, a ramp), the flattening of any trajectory to a
// level road, and the car rig's drive along a trajectory (part of the one pose-level generator,
// synthetic.h).
//
// Frames: every camera frame is KITTI's (x right, y down, z forward), so on a level road the
// vertical is the cameras' y axis and a car's yaw is a rotation about y. World frames of the
// trajectories are the master's first pose.

#include <string>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {

// Front camera (master, "front") and three slaves in the master frame, metres: "left" and
// "right" (mirror cameras looking sideways, pitched down, 0.3 m lower), "rear" (looking back,
// 3.8 m behind). Different odometry scales. Names: CarRigNames().
std::vector<Similarity> CarRig();
std::vector<std::string> CarRigNames();

// A car driving on a level road: speed `speed_mps`, yaw rate a sum of sinusoids around a
// steady turn (up to ~25 deg/s, loops of ~90 m radius), sampled at `rate_hz` for `duration_s`.
// With ramp_at_s >= 0 the car stops turning at that time and drives straight up a ramp: it
// pitches up to `ramp_slope_deg` over `ramp_transition_s`, climbs for `ramp_length_s`, pitches
// back to level and turns again.
struct CarPathOptions {
  double duration_s = 240.0;
  double rate_hz = 20.0;
  double speed_mps = 8.0;
  double ramp_at_s = -1.0;
  double ramp_slope_deg = 6.0;
  double ramp_transition_s = 3.0;
  double ramp_length_s = 15.0;
};
// The master's path (world_from_master, world = its first pose, stamps from 0).
SampledTrajectory CarPath(const CarPathOptions& options);

// The same poses flattened to a level road: the rotation reduced to its yaw about the world's
// y axis (the heading of the camera's z axis in the x-z plane) and the height (y) set to 0.
SampledTrajectory FlattenToYaw(const SampledTrajectory& trajectory);

// The car rig (CarRigNames(), CarRig()) driven along `path`: GenerateDriveAlong with the
// odometry errors, seed and segments of `options`.
SyntheticDrive DriveCarRig(const SampledTrajectory& path, const DriveOptions& options);

}  // namespace rigcal
