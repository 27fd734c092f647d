// SPDX-License-Identifier: Apache-2.0
#include "support/pinhole_intrinsics.h"

namespace rigcal::support {

Expected<PinholeIntrinsics> PinholeOf(const camera::CameraModel& camera) {
  const auto centre = camera.Project(Eigen::Vector3d(0, 0, 1));
  const auto right = camera.Project(Eigen::Vector3d(0.1, 0, 1));
  const auto down = camera.Project(Eigen::Vector3d(0, 0.1, 1));
  const auto off_axis = camera.Project(Eigen::Vector3d(0.3, -0.2, 1));
  if (!centre || !right || !down || !off_axis) return Error{"the camera does not project"};
  const PinholeIntrinsics k{10.0 * (right->x() - centre->x()), 10.0 * (down->y() - centre->y()),
                            centre->x(), centre->y()};
  const Eigen::Vector2d pinhole(k.fx * 0.3 + k.cx, k.fy * -0.2 + k.cy);
  if ((pinhole - *off_axis).norm() > 1e-6) {
    return Error{"needs a pinhole camera without lens distortion"};
  }
  return k;
}

}  // namespace rigcal::support
