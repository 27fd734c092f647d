// SPDX-License-Identifier: Apache-2.0
// Per-view PnP poses of a calibrated camera.
#include "rigcal/pattern/target_poses.h"

#include <cmath>
#include <limits>

#include "opencv.h"
#include "planar_pose.h"

namespace rigcal::pattern {

using camera::CameraSpec;

namespace {

ViewStatistics StatisticsOf(const TargetView& view) {
  ViewStatistics stats;
  stats.file = view.file;
  stats.t_ns = view.t_ns;
  stats.corners = static_cast<int>(view.pixels.size());
  return stats;
}

// Any camera model (used for scaramuzza, which OpenCV's PnP cannot take): internal::
// EstimatePlanarPose per view.
Expected<std::vector<ViewStatistics>> PlanarPoses(const CameraViews& views, const CameraSpec& spec,
                                                  double max_rms_px) {
  auto model = camera::MakeCameraModel(spec);
  if (!model) return Error{views.camera + ": " + model.error()};
  std::vector<ViewStatistics> out;
  out.reserve(views.views.size());
  for (const TargetView& view : views.views) {
    ViewStatistics stats = StatisticsOf(view);
    if (auto pose = internal::EstimatePlanarPose(**model, view); pose) {
      stats.rms_px = pose->rms_px;
      stats.max_px = pose->max_px;
      stats.target_from_cam.q = Eigen::Quaterniond(pose->cam_from_target_rotation.transpose()).normalized();
      stats.target_from_cam.C = -pose->cam_from_target_rotation.transpose() * pose->cam_from_target_translation;
      stats.used = std::isfinite(stats.rms_px) && stats.rms_px <= max_rms_px;
    }
    out.push_back(stats);
  }
  return out;
}

}  // namespace

Expected<std::vector<ViewStatistics>> EstimateTargetPoses(const CameraViews& views,
                                                          const CameraSpec& spec,
                                                          double max_rms_px) {
  if (spec.width != views.width || spec.height != views.height) {
    return Error{views.camera + ": the views are " + std::to_string(views.width) + "x" +
                 std::to_string(views.height) + " but the camera's intrinsics are for " +
                 std::to_string(spec.width) + "x" + std::to_string(spec.height)};
  }
  if (spec.model == CameraSpec::Model::kScaramuzza) return PlanarPoses(views, spec, max_rms_px);
  const cv::Matx33d K(spec.intrinsics[0], 0.0, spec.intrinsics[2], 0.0, spec.intrinsics[1],
                      spec.intrinsics[3], 0.0, 0.0, 1.0);
  const bool fisheye = spec.model == CameraSpec::Model::kFisheye;
  cv::Mat dist = cv::Mat::zeros(fisheye ? 4 : 5, 1, CV_64F);
  for (size_t i = 0; i < spec.distortion.size() && i < 5; ++i) {
    dist.at<double>(static_cast<int>(i)) = spec.distortion[i];
  }
  std::vector<ViewStatistics> out;
  out.reserve(views.views.size());
  for (const TargetView& view : views.views) {
    ViewStatistics stats = StatisticsOf(view);
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    for (size_t j = 0; j < view.pixels.size(); ++j) {
      object.emplace_back(view.target_points[j].x(), view.target_points[j].y(),
                          view.target_points[j].z());
      image.emplace_back(view.pixels[j].x(), view.pixels[j].y());
    }
    // PnP on undistorted normalised points for both models (K = I, no distortion), then the
    // reprojection error through the full model.
    std::vector<cv::Point2d> normalised;
    if (fisheye) {
      cv::fisheye::undistortPoints(image, normalised, K, dist);
    } else {
      cv::undistortPoints(image, normalised, K, dist);
    }
    cv::Mat rvec;
    cv::Mat tvec;
    bool ok = false;
    try {
      ok = cv::solvePnP(object, normalised, cv::Matx33d::eye(), cv::noArray(), rvec, tvec, false,
                        cv::SOLVEPNP_IPPE);
      if (ok && !fisheye) {
        ok = cv::solvePnP(object, image, K, dist, rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
      }
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (ok) {
      std::vector<cv::Point2d> projected;
      if (fisheye) {
        cv::fisheye::projectPoints(object, projected, rvec, tvec, K, dist);
      } else {
        cv::projectPoints(object, rvec, tvec, K, dist, projected);
      }
      double sum_sq = 0.0;
      double max_err = 0.0;
      for (size_t j = 0; j < image.size(); ++j) {
        const double e = cv::norm(projected[j] - image[j]);
        sum_sq += e * e;
        max_err = std::max(max_err, e);
      }
      stats.rms_px = std::sqrt(sum_sq / static_cast<double>(image.size()));
      stats.max_px = max_err;
      cv::Matx33d cam_from_target;
      cv::Rodrigues(rvec, cam_from_target);
      Eigen::Matrix3d R;
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R(r, c) = cam_from_target(r, c);
      }
      const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
      stats.target_from_cam.q = Eigen::Quaterniond(R.transpose()).normalized();
      stats.target_from_cam.C = -R.transpose() * t;
      stats.used = std::isfinite(stats.rms_px) && stats.rms_px <= max_rms_px;
    }
    out.push_back(stats);
  }
  return out;
}

TimedTrajectory PosesAsTrajectory(const std::string& camera,
                                         const std::vector<ViewStatistics>& views,
                                         double max_rms_px) {
  TimedTrajectory trajectory;
  trajectory.name = camera;
  for (const ViewStatistics& v : views) {
    if (v.rejected || !std::isfinite(v.rms_px)) continue;
    if (!std::isnan(max_rms_px) && v.rms_px > max_rms_px) continue;
    if (!trajectory.t_ns.empty() && v.t_ns <= trajectory.t_ns.back()) continue;  // duplicate key
    trajectory.t_ns.push_back(v.t_ns);
    trajectory.poses.push_back(v.target_from_cam);
    trajectory.segment.push_back(0);
  }
  return trajectory;
}

TimedTrajectory CameraLocal(const TimedTrajectory& poses) {
  TimedTrajectory local = poses;
  if (poses.poses.empty()) return local;
  const Pose first_inverse = poses.poses.front().Inverse();
  for (Pose& p : local.poses) p = first_inverse * p;
  return local;
}

}  // namespace rigcal::pattern
