// SPDX-License-Identifier: Apache-2.0
#pragma once
// OpenCV for the target module, with the warnings of its 4.6 headers silenced, and the
// conversions between Eigen and OpenCV types used here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include <Eigen/Core>
#include <vector>

#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern::internal {

inline std::vector<cv::Point2f> ImagePoints(const TargetView& view) {
  std::vector<cv::Point2f> out;
  out.reserve(view.pixels.size());
  for (const Eigen::Vector2d& p : view.pixels) out.emplace_back(float(p.x()), float(p.y()));
  return out;
}

inline std::vector<cv::Point3f> ObjectPoints(const TargetView& view) {
  std::vector<cv::Point3f> out;
  out.reserve(view.target_points.size());
  for (const Eigen::Vector3d& p : view.target_points) {
    out.emplace_back(float(p.x()), float(p.y()), float(p.z()));
  }
  return out;
}

}  // namespace rigcal::pattern::internal
