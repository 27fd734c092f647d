// SPDX-License-Identifier: Apache-2.0
// Ideal pinhole and equidistant cameras built by rigcal_camera's factory (ideal_cameras.h).
#include "support/ideal_cameras.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rigcal/camera/camera_spec.h"

namespace rigcal::support {
namespace {

std::shared_ptr<const camera::CameraModel> Make(const camera::CameraSpec& spec) {
  return std::shared_ptr<const camera::CameraModel>(camera::MakeCameraModel(spec).value());
}

}  // namespace

std::shared_ptr<const camera::CameraModel> IdealPinhole(int width, int height, double fx, double fy,
                                                        double cx, double cy) {
  camera::CameraSpec spec;
  spec.name = "ideal pinhole";
  spec.model = camera::CameraSpec::Model::kPinhole;
  spec.width = width;
  spec.height = height;
  spec.intrinsics = {fx, fy, cx, cy};
  return Make(spec);
}

std::shared_ptr<const camera::CameraModel> PinholeWithFov(int width, int height, double hfov_deg) {
  const double f = 0.5 * width / std::tan(0.5 * hfov_deg * std::numbers::pi / 180.0);
  return IdealPinhole(width, height, f, f, 0.5 * (width - 1), 0.5 * (height - 1));
}

std::shared_ptr<const camera::CameraModel> IdealEquidistant(int width, int height, double f,
                                                            double max_angle_deg) {
  camera::CameraSpec spec;
  spec.name = "ideal equidistant";
  spec.model = camera::CameraSpec::Model::kFisheye;
  spec.width = width;
  spec.height = height;
  spec.intrinsics = {f, f, 0.5 * (width - 1), 0.5 * (height - 1)};
  spec.max_field_angle_deg = max_angle_deg;
  return Make(spec);
}

std::shared_ptr<const camera::CameraModel> EquidistantWithFov(int width, int height,
                                                              double fov_deg) {
  const double half = 0.5 * fov_deg * std::numbers::pi / 180.0;
  return IdealEquidistant(width, height, 0.5 * std::min(width, height) / half, 0.5 * fov_deg);
}

}  // namespace rigcal::support
