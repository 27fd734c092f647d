#pragma once
// Ground-vehicle fixtures for the planar-motion tests: a four-camera car rig, car-like master
// trajectories (flat roads, a ramp) and the real KITTI 00 trajectory, plain and flattened to
// pure yaw.
//
// Frames: every camera frame is KITTI's (x right, y down, z forward), so on a level road the
// vertical is the cameras' y axis and a car's yaw is a rotation about y. World frames of the
// trajectories are the master's first pose.

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/calib/status.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/types.h"

namespace rigcal::support {

// Front camera (master, "front") and three slaves in the master frame, metres: "left" and
// "right" (mirror cameras looking sideways, pitched down, 0.3 m lower), "rear" (looking back,
// 3.8 m behind). Different odometry scales. Names: CarRigNames().
std::vector<Similarity> CarRig();
std::vector<std::string> CarRigNames();

// A master trajectory sampled at t_ns (world_from_master).
struct Trajectory {
  std::vector<int64_t> t_ns;
  std::vector<Pose> poses;
};

// A car driving on a level road: speed `speed_mps`, yaw rate a sum of sinusoids around a
// steady turn (up to ~25 deg/s, loops of ~90 m radius), sampled at `rate_hz` for `duration_s`. With
// ramp_at_s >= 0 the car stops turning at that time and drives straight up a ramp: it pitches up to
// `ramp_slope_deg` over `ramp_transition_s`, climbs for `ramp_length_s`, pitches back to level and
// turns again.
struct CarPathOptions {
  double duration_s = 240.0;
  double rate_hz = 20.0;
  double speed_mps = 8.0;
  double ramp_at_s = -1.0;
  double ramp_slope_deg = 6.0;
  double ramp_transition_s = 3.0;
  double ramp_length_s = 15.0;
};
Trajectory CarPath(const CarPathOptions& options);

// The KITTI odometry sequence 00 ground truth from <RIGCAL_SHARED_DATA_DIR>/trajectories/
// (KITTI_00_gt.txt and KITTI_00_gt_times.txt). Error (with the reason) when it is absent.
Expected<Trajectory> LoadKitti00();

// The same poses flattened to a level road: the rotation reduced to its yaw about the world's
// y axis (the heading of the camera's z axis in the x-z plane) and the height (y) set to 0.
Trajectory FlattenToYaw(const Trajectory& trajectory);

// The car rig driven along `trajectory` with odometry-like white noise per pose.
SyntheticDrive DriveCarRig(const Trajectory& trajectory, double rotation_noise_deg,
                           double position_noise, uint64_t seed = 1);

// σ-free summary of an estimate against the truth, split at the planar axis (unit, master
// frame): rotation error (deg), error of C in the plane and along the axis, scale error (%).
struct PlanarErrors {
  double rot_deg = 0.0;
  double plane = 0.0;
  double axis = 0.0;
  double scale_pct = 0.0;
};
PlanarErrors ErrorsAlongAxis(const Similarity& estimate, const Similarity& truth,
                             const Eigen::Vector3d& axis);

}  // namespace rigcal::support
