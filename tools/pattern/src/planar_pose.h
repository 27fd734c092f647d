// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pose of a planar target seen by any camera model, from bearings: a direct linear
// transform b x (H [X Y 1]^T) = 0 on the unit bearings of the corners (valid beyond 90 degrees
// of field angle, where undistorted image coordinates do not exist), then Gauss-Newton with
// Levenberg damping on the reprojection error through the model. Used for the omnidirectional
// (scaramuzza) cameras, whose views OpenCV's PnP cannot take.

#include <Eigen/Core>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_model.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern::internal {

// True when every corner of `view` lies on the target's z = 0 plane (to 1e-9 relative).
bool OnTargetPlane(const TargetView& view);

struct PlanarPose {
  // cam_from_target: x_cam = cam_from_target_rotation x_target + cam_from_target_translation.
  Eigen::Matrix3d cam_from_target_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d cam_from_target_translation = Eigen::Vector3d::Zero();
  double rms_px = 0.0;
  double max_px = 0.0;
};

// Errors: fewer than 4 corners, corners off the target's z = 0 plane, a pixel the model cannot
// unproject, a degenerate configuration (collinear corners), or a pose under which a corner
// does not project.
Expected<PlanarPose> EstimatePlanarPose(const camera::CameraModel& model, const TargetView& view);

}  // namespace rigcal::pattern::internal
