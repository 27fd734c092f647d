// SPDX-License-Identifier: Apache-2.0
#pragma once
// Per-view target poses (PnP) of a camera with known intrinsics, as a trajectory: the camera's
// pose in the target frame at every view (q: target_from_cam, C: camera centre in the target
// frame, in the target's unit). Used as the master's metric reference (metric_scale.h), as the
// input of the target-based reference (reference_calibration.h) and, relative to the first
// view, as camera-local odometry for the motion-based calibration.

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/pattern/intrinsics.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern {

// PnP for every view: OpenCV IPPE for the planar target, refined by Levenberg-Marquardt on the
// reprojection error, distortion of `spec` applied (pinhole, fisheye); for scaramuzza a direct
// linear transform on the corners' bearings refined on the reprojection error through the model.
// Statistics as CalibrateIntrinsics' views (used = the pose is kept: its RMS is at most
// `max_rms_px`). Errors: a spec whose resolution differs from the views', or one that is not a
// valid camera.
Expected<std::vector<ViewStatistics>> EstimateTargetPoses(const CameraViews& views,
                                                          const camera::CameraSpec& spec,
                                                          double max_rms_px = 2.0);

// The poses of `views` that are not rejected and have an RMS of at most `max_rms_px` (NaN: no
// limit) as a trajectory named `camera`, stamps = the views' t_ns (a repeated key keeps the first).
TimedTrajectory PosesAsTrajectory(const std::string& camera,
                                         const std::vector<ViewStatistics>& views,
                                         double max_rms_px);

// The poses of a camera relative to its first: T_0^-1 T_k (thesis 4.2, camera-local poses), the
// input of the motion-based calibration, which then uses no shared observation.
TimedTrajectory CameraLocal(const TimedTrajectory& poses);

}  // namespace rigcal::pattern
