// SPDX-License-Identifier: Apache-2.0
#pragma once
// Ideal (distortion-free) cameras of rigcal_camera for the simulated-rig, VO and benchmark
// fixtures: a pinhole and an equidistant ("f-theta") fisheye that may see beyond 180 degrees.
// They are the real models (camera_spec.h, tested against their equations in tests/camera/)
// with zero distortion. A spec the model factory rejects throws (BadExpectedAccess).

#include <memory>

#include "rigcal/camera/camera_model.h"

namespace rigcal::support {

// Pinhole u = fx x / z + cx, v = fy y / z + cy; its field of view is the whole image.
std::shared_ptr<const camera::CameraModel> IdealPinhole(int width, int height, double fx, double fy,
                                                        double cx, double cy);
// Square pixels, principal point at the image centre ((width - 1) / 2, (height - 1) / 2),
// horizontal field of view `hfov_deg` across the image width: f = width / 2 / tan(hfov / 2).
std::shared_ptr<const camera::CameraModel> PinholeWithFov(int width, int height, double hfov_deg);

// Equidistant fisheye r = f theta (Kannala-Brandt without distortion), principal point at the
// image centre, valid up to `max_angle_deg` from the optical axis (may exceed 90).
std::shared_ptr<const camera::CameraModel> IdealEquidistant(int width, int height, double f,
                                                            double max_angle_deg);
// An equidistant fisheye of `fov_deg` whose image circle fills the smaller image side:
// f = min(width, height) / 2 / (fov / 2 in radians), max angle fov / 2.
std::shared_ptr<const camera::CameraModel> EquidistantWithFov(int width, int height,
                                                              double fov_deg);

}  // namespace rigcal::support
