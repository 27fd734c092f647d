// SPDX-License-Identifier: Apache-2.0
#pragma once
// The real KITTI odometry sequence 00 ground truth as a master trajectory for the planar-motion
// tests (data, read from the shared data folder; the synthetic car rig that drives along it is
// in rigcal/calib/synthetic_car.h).

#include "rigcal/base/status.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal::support {

// The KITTI odometry sequence 00 ground truth from <RIGCAL_SHARED_DATA_DIR>/trajectories/
// (KITTI_00_gt.txt and KITTI_00_gt_times.txt): world_from_camera in KITTI's camera frame (x
// right, y down, z forward). Error (with the reason) when it is absent.
Expected<SampledTrajectory> LoadKitti00();

}  // namespace rigcal::support
