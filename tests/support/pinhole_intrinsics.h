// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pinhole intrinsics of a camera model without lens distortion, for evaluation code that
// projects with its own (templated, auto-differentiated) pinhole.

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::support {

struct PinholeIntrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels
};

// fx, fy, cx, cy of `camera`, or an error when it does not project like a pinhole without
// distortion (checked at a point 17 degrees off the axis, to 1e-6 px).
Expected<PinholeIntrinsics> PinholeOf(const camera::CameraModel& camera);

}  // namespace rigcal::support
