// SPDX-License-Identifier: Apache-2.0
#pragma once
// Simulated views of the 9x6 chessboard (0.04 m squares) by a pinhole (radtan) or equidistant
// fisheye camera: OpenCV projects the corners (the convention the target module uses), then
// pixel noise is added (support/pixel_noise.h). Shared by the target module's tests. Header-only.

#include <Eigen/Geometry>
#include <cstdint>
#include <random>
#include <string>
#include <utility>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#pragma GCC diagnostic pop

#include "rigcal/base/types.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/pattern/target_views.h"
#include "support/pixel_noise.h"

namespace rigcal::test_support {

// A 752x480 camera with EuRoC-like intrinsics; radtan distortion for the pinhole model,
// equidistant coefficients for the fisheye.
inline camera::CameraSpec EurocLikeCamera(const std::string& name,
                                          camera::CameraSpec::Model model) {
  camera::CameraSpec spec;
  spec.name = name;
  spec.model = model;
  spec.width = 752;
  spec.height = 480;
  spec.intrinsics = {458.0, 457.0, 367.0, 248.0};
  spec.distortion = model == camera::CameraSpec::Model::kFisheye
                        ? std::vector<double>{-0.01, 0.02, -0.005, 0.001}
                        : std::vector<double>{-0.28, 0.074, 2e-4, -3e-4};
  return spec;
}

// The board's corners seen by `spec` with the board at `cam_from_target` (q: rotation, C: the
// board's origin in the camera), plus noise of `noise_px` per axis (none when 0); stamped
// `t_ns`, named `file`.
inline pattern::TargetView ProjectBoard(const camera::CameraSpec& spec, const Pose& cam_from_target,
                                       std::mt19937& rng, double noise_px, int64_t t_ns,
                                       std::string file) {
  std::vector<cv::Point3d> object;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) object.emplace_back(0.04 * c, 0.04 * r, 0.0);
  }
  const Eigen::AngleAxisd aa(cam_from_target.q);
  const Eigen::Vector3d r = aa.angle() * aa.axis();
  const cv::Vec3d rvec(r.x(), r.y(), r.z());
  const cv::Vec3d tvec(cam_from_target.C.x(), cam_from_target.C.y(), cam_from_target.C.z());
  const cv::Matx33d K(spec.intrinsics[0], 0, spec.intrinsics[2], 0, spec.intrinsics[1],
                      spec.intrinsics[3], 0, 0, 1);
  std::vector<cv::Point2d> image;
  if (spec.model == camera::CameraSpec::Model::kFisheye) {
    cv::fisheye::projectPoints(object, image, rvec, tvec, K, cv::Vec4d(spec.distortion.data()));
  } else {
    cv::projectPoints(object, rvec, tvec, K, spec.distortion, image);
  }
  PixelNoise noise(noise_px);
  pattern::TargetView view;
  view.t_ns = t_ns;
  view.file = std::move(file);
  for (size_t j = 0; j < object.size(); ++j) {
    view.pixels.push_back(Eigen::Vector2d(image[j].x, image[j].y) + noise(rng));
    view.target_points.emplace_back(object[j].x, object[j].y, object[j].z);
  }
  return view;
}

}  // namespace rigcal::test_support
