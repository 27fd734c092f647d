// SPDX-License-Identifier: Apache-2.0
#pragma once
// Simulated views of a 9x6 board (0.04 spacing) by an omnidirectional camera: rigcal's own
// scaramuzza model projects the corners, Gaussian pixel noise is added. The board is placed
// 0.2-0.4 away with its centre 0..85 degrees off the optical axis in every direction and
// tilted by up to 0.6 rad; a view with a corner outside the image (5 px margin) or the model's
// field of view is drawn again. And two scores of an estimated model against the truth.

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "rigcal/camera/camera_spec.h"
#include "rigcal/pattern/target_views.h"
#include "support/pixel_noise.h"

namespace rigcal::test_support {

struct BoardPose {
  Eigen::Matrix3d R;  // camera from board
  Eigen::Vector3d t;
};

// A 200-degree lens: an equidistant-like polynomial (f 180 px) on an 800x600 image, centre
// 12 px off the image centre, affine c = 1.004, d = 0.003.
inline camera::CameraSpec WideOmniCamera(const std::string& name) {
  auto spec = camera::ScaramuzzaSpecForEquidistant(name, 800, 600, 180.0, 411.5, 287.5, 100.0);
  camera::CameraSpec out = spec.ok() ? *spec : camera::CameraSpec{};
  out.affine = {1.004, 0.003, 0.0};
  return out;
}

inline pattern::CameraViews SimulatedOmniViews(const camera::CameraSpec& spec, int n, unsigned seed,
                                              double noise_px,
                                              std::vector<BoardPose>* poses = nullptr) {
  pattern::CameraViews views;
  views.camera = spec.name;
  views.width = spec.width;
  views.height = spec.height;
  auto model = camera::MakeCameraModel(spec);
  if (!model.ok()) return views;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> off_axis(0.0, 85.0 * M_PI / 180.0);
  std::uniform_real_distribution<double> azimuth(-M_PI, M_PI);
  std::uniform_real_distribution<double> tilt(-0.6, 0.6);
  std::uniform_real_distribution<double> depth(0.2, 0.4);
  PixelNoise noise(noise_px);
  const Eigen::Vector3d board_centre(0.16, 0.10, 0.0);
  while (static_cast<int>(views.views.size()) < n) {
    const double a = off_axis(rng);
    const double phi = azimuth(rng);
    const Eigen::Vector3d direction(std::sin(a) * std::cos(phi), std::sin(a) * std::sin(phi),
                                    std::cos(a));
    // Board normal along the line of sight, then tilted.
    Eigen::Vector3d x_board = Eigen::Vector3d::UnitX() - direction.x() * direction;
    if (x_board.norm() < 0.1) x_board = Eigen::Vector3d::UnitY() - direction.y() * direction;
    x_board.normalize();
    Eigen::Matrix3d R;
    R.col(0) = x_board;
    R.col(1) = direction.cross(x_board);
    R.col(2) = direction;
    const double tilt_x = tilt(rng);
    const double tilt_y = tilt(rng);
    R = R * Eigen::AngleAxisd(tilt_x, Eigen::Vector3d::UnitX()).toRotationMatrix() *
        Eigen::AngleAxisd(tilt_y, Eigen::Vector3d::UnitY()).toRotationMatrix();
    const Eigen::Vector3d t = depth(rng) * direction - R * board_centre;
    pattern::TargetView view;
    bool inside = true;
    for (int r = 0; r < 6 && inside; ++r) {
      for (int c = 0; c < 9 && inside; ++c) {
        const Eigen::Vector3d X(0.04 * c, 0.04 * r, 0.0);
        const auto pixel = (*model)->Project(R * X + t);
        inside = pixel && (*model)->InImage(*pixel, 5.0);
        if (!inside) break;
        view.pixels.push_back(*pixel + noise(rng));
        view.target_points.push_back(X);
      }
    }
    if (!inside) continue;
    view.t_ns = static_cast<int64_t>(views.views.size() + 1) * 1000000000LL;
    view.file = "view" + std::to_string(views.views.size());
    views.views.push_back(std::move(view));
    if (poses != nullptr) poses->push_back({R, t});
  }
  return views;
}

// Worst pixel distance between two models over bearings up to `max_deg` that the truth projects
// into the image.
inline double WorstProjectionDifference(const camera::CameraSpec& truth,
                                        const camera::CameraSpec& estimate, double max_deg,
                                        int* count) {
  auto a = camera::MakeCameraModel(truth);
  auto b = camera::MakeCameraModel(estimate);
  if (!a.ok() || !b.ok()) return std::numeric_limits<double>::infinity();
  double worst = 0.0;
  *count = 0;
  for (double deg = 0.0; deg <= max_deg; deg += 5.0) {
    for (int k = 0; k < 24; ++k) {
      const double theta = deg * M_PI / 180.0;
      const double phi = k * M_PI / 12.0;
      const Eigen::Vector3d bearing(std::sin(theta) * std::cos(phi),
                                    std::sin(theta) * std::sin(phi), std::cos(theta));
      const auto p = (*a)->Project(bearing);
      if (!p || !(*a)->InImage(*p)) continue;
      const auto q = (*b)->Project(bearing);
      if (!q) return std::numeric_limits<double>::infinity();
      worst = std::max(worst, (*p - *q).norm());
      ++*count;
    }
  }
  return worst;
}

// RMS pixel distance at the corners' true bearings, after the rotation between the two camera
// frames that best aligns the bearings both models give the corners' pixels.
inline double AlignedRmsAtCorners(const camera::CameraSpec& truth,
                                  const camera::CameraSpec& estimate,
                                  const pattern::CameraViews& views) {
  auto a = camera::MakeCameraModel(truth);
  auto b = camera::MakeCameraModel(estimate);
  if (!a.ok() || !b.ok()) return std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> bearings;
  Eigen::Matrix3d correlation = Eigen::Matrix3d::Zero();
  for (const pattern::TargetView& v : views.views) {
    for (const Eigen::Vector2d& p : v.pixels) {
      const auto truth_bearing = (*a)->Unproject(p);
      const auto estimate_bearing = (*b)->Unproject(p);
      if (!truth_bearing || !estimate_bearing) return std::numeric_limits<double>::infinity();
      bearings.push_back(*truth_bearing);
      correlation += *estimate_bearing * truth_bearing->transpose();
    }
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(correlation,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
  double sum_sq = 0.0;
  for (const Eigen::Vector3d& bearing : bearings) {
    const auto p = (*a)->Project(bearing);
    const auto q = (*b)->Project(R * bearing);
    if (!p || !q) return std::numeric_limits<double>::infinity();
    sum_sq += (*p - *q).squaredNorm();
  }
  return std::sqrt(sum_sq / static_cast<double>(bearings.size()));
}

}  // namespace rigcal::test_support
