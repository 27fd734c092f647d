// SPDX-License-Identifier: Apache-2.0
#include "support/offline_bundle_adjustment.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <optional>
#include <string>

#include "rigcal/base/robust_statistics.h"
#include "support/ceres_transform.h"
#include "support/pinhole_intrinsics.h"

namespace rigcal::support {
namespace {

constexpr double kDegToRad = 3.14159265358979323846 / 180.0;

struct Observation {
  int frame = 0;
  Eigen::Vector2d px;
};
using Track = std::vector<Observation>;

// KLT tracks through frames first..last, new corners where fewer than max_corners are alive.
std::vector<Track> TrackCorners(const std::vector<cv::Mat>& grey, int first, int last,
                                const OfflineBaOptions& o) {
  std::vector<Track> tracks;
  std::vector<cv::Point2f> alive;
  std::vector<int> alive_track;
  for (int k = first; k <= last; ++k) {
    const cv::Mat& image = grey[static_cast<size_t>(k)];
    if (k > first && !alive.empty()) {
      std::vector<cv::Point2f> next, back;
      std::vector<uchar> found, found_back;
      std::vector<float> error;
      const cv::Mat& previous = grey[static_cast<size_t>(k - 1)];
      cv::calcOpticalFlowPyrLK(previous, image, alive, next, found, error, cv::Size(21, 21), 3);
      cv::calcOpticalFlowPyrLK(image, previous, next, back, found_back, error, cv::Size(21, 21), 3);
      std::vector<cv::Point2f> kept;
      std::vector<int> kept_track;
      const cv::Rect2f inside(4.0F, 4.0F, image.cols - 8.0F, image.rows - 8.0F);
      for (size_t i = 0; i < alive.size(); ++i) {
        if (!found[i] || !found_back[i] || cv::norm(back[i] - alive[i]) > o.max_fb_error_px ||
            !inside.contains(next[i])) {
          continue;
        }
        kept.push_back(next[i]);
        kept_track.push_back(alive_track[i]);
        tracks[static_cast<size_t>(alive_track[i])].push_back({k, {next[i].x, next[i].y}});
      }
      alive = std::move(kept);
      alive_track = std::move(kept_track);
    }
    if (static_cast<int>(alive.size()) >= o.max_corners * 4 / 5) continue;
    cv::Mat mask(image.size(), CV_8U, cv::Scalar(255));
    for (const cv::Point2f& p : alive) cv::circle(mask, p, 10, cv::Scalar(0), -1);
    std::vector<cv::Point2f> fresh;
    cv::goodFeaturesToTrack(image, fresh, o.max_corners - static_cast<int>(alive.size()), 0.005, 10,
                            mask);
    for (const cv::Point2f& p : fresh) {
      alive.push_back(p);
      alive_track.push_back(static_cast<int>(tracks.size()));
      tracks.push_back({{k, {p.x, p.y}}});
    }
  }
  return tracks;
}

// Camera from world.
struct Camera : CeresTransform {
  Eigen::Vector3d Centre() const { return -(Q().conjugate() * T()); }
};

Camera CameraFrom(const Pose& world_from_cam) {
  return Camera{CeresTransform::FromPose(world_from_cam.Inverse())};
}

struct ReprojectionCost {
  Eigen::Vector2d px;
  PinholeIntrinsics k;

  template <typename T>
  bool operator()(const T* q, const T* t, const T* point, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> cam_from_world(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> translation(t), x(point);
    const Eigen::Matrix<T, 3, 1> p = cam_from_world * x + translation;
    residual[0] = T(k.fx) * p.x() / p.z() + T(k.cx) - T(px.x());
    residual[1] = T(k.fy) * p.y() / p.z() + T(k.cy) - T(px.y());
    return true;
  }
};

// The distance between two cameras' centres held at `length` (the gauge's scale).
struct BaselineCost {
  double length;

  template <typename T>
  bool operator()(const T* q0, const T* t0, const T* q1, const T* t1, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> a(q0), b(q1);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ta(t0), tb(t1);
    const Eigen::Matrix<T, 3, 1> centre_a = -(a.conjugate() * ta), centre_b = -(b.conjugate() * tb);
    residual[0] = T(1e3) * ((centre_b - centre_a).norm() - T(length));
    return true;
  }
};

double Reprojection(const Camera& c, const Eigen::Vector3d& x, const Observation& o,
                    const PinholeIntrinsics& k) {
  if ((c.Q() * x + c.T()).z() <= 0.0) return 1e9;  // behind the camera
  double e[2];
  ReprojectionCost{o.px, k}(c.q.data(), c.t.data(), x.data(), e);
  return std::hypot(e[0], e[1]);
}

// Linear (DLT) triangulation of a track at the cameras, if it passes the options' gates.
std::optional<Eigen::Vector3d> Triangulate(const Track& track, const std::map<int, Camera>& cams,
                                           const PinholeIntrinsics& k, const OfflineBaOptions& o) {
  if (static_cast<int>(track.size()) < o.min_observations) return std::nullopt;
  Eigen::Matrix4d a = Eigen::Matrix4d::Zero();
  for (const Observation& obs : track) {
    const Camera& c = cams.at(obs.frame);
    Eigen::Matrix<double, 3, 4> p;
    p << c.Q().toRotationMatrix(), c.T();
    const double x = (obs.px.x() - k.cx) / k.fx, y = (obs.px.y() - k.cy) / k.fy;
    Eigen::Matrix<double, 2, 4> rows;
    rows << x * p.row(2) - p.row(0), y * p.row(2) - p.row(1);
    a += rows.transpose() * rows;
  }
  const Eigen::Vector4d h = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(a).eigenvectors().col(0);
  if (std::abs(h(3)) < 1e-12) return std::nullopt;
  const Eigen::Vector3d x = h.head<3>() / h(3);
  const Eigen::Vector3d first = cams.at(track.front().frame).Centre();
  const Eigen::Vector3d last = cams.at(track.back().frame).Centre();
  const double ray_angle =
      std::acos(std::clamp((x - first).normalized().dot((x - last).normalized()), -1.0, 1.0));
  if (ray_angle < o.min_ray_angle_deg * kDegToRad) return std::nullopt;
  for (const Observation& obs : track) {
    if (Reprojection(cams.at(obs.frame), x, obs, k) > o.initial_gate_px) return std::nullopt;
  }
  return x;
}

struct Adjustment {
  std::map<int, Camera> cams;
  std::vector<Eigen::Vector3d> points;
  std::vector<const Track*> tracks;
};

void Solve(double huber_px, double baseline, const PinholeIntrinsics& k, Adjustment* a) {
  ceres::Problem problem;
  for (size_t i = 0; i < a->points.size(); ++i) {
    for (const Observation& obs : *a->tracks[i]) {
      Camera& c = a->cams.at(obs.frame);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 4, 3, 3>(
                                   new ReprojectionCost{obs.px, k}),
                               new ceres::HuberLoss(huber_px), c.q.data(), c.t.data(),
                               a->points[i].data());
    }
  }
  Camera& first = a->cams.begin()->second;
  Camera& last = a->cams.rbegin()->second;
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<BaselineCost, 1, 4, 3, 4, 3>(new BaselineCost{baseline}),
      nullptr, first.q.data(), first.t.data(), last.q.data(), last.t.data());
  for (auto& [frame, c] : a->cams) {
    if (problem.HasParameterBlock(c.q.data())) {
      problem.SetManifold(c.q.data(), new ceres::EigenQuaternionManifold);
    }
  }
  problem.SetParameterBlockConstant(first.q.data());
  problem.SetParameterBlockConstant(first.t.data());
  SolveAdjustment(&problem);
}

double ResidualSigma(const Adjustment& a, const PinholeIntrinsics& k) {
  std::vector<double> r;
  for (size_t i = 0; i < a.points.size(); ++i) {
    for (const Observation& obs : *a.tracks[i]) {
      double e[2];
      const Camera& c = a.cams.at(obs.frame);
      ReprojectionCost{obs.px, k}(c.q.data(), c.t.data(), a.points[i].data(), e);
      r.push_back(std::abs(e[0]));
      r.push_back(std::abs(e[1]));
    }
  }
  return 1.4826 * Median(std::move(r));  // σ of zero-mean Gaussian residuals, robustly
}

// Drops the tracks whose residuals together do not fit σ (OfflineBaOptions::prune_rounds).
void PruneTracks(const PinholeIntrinsics& k, double sigma_px, Adjustment* a) {
  std::vector<Eigen::Vector3d> points;
  std::vector<const Track*> tracks;
  for (size_t i = 0; i < a->points.size(); ++i) {
    double sum2 = 0.0;
    for (const Observation& obs : *a->tracks[i]) {
      double e[2];
      const Camera& c = a->cams.at(obs.frame);
      ReprojectionCost{obs.px, k}(c.q.data(), c.t.data(), a->points[i].data(), e);
      sum2 += e[0] * e[0] + e[1] * e[1];
    }
    const double rms_px = std::sqrt(sum2 / (2.0 * static_cast<double>(a->tracks[i]->size())));
    if (rms_px <= 2.0 * sigma_px) {
      points.push_back(a->points[i]);
      tracks.push_back(a->tracks[i]);
    }
  }
  a->points.swap(points);
  a->tracks.swap(tracks);
}

}  // namespace

Expected<OfflineBaResult> OfflineBundleAdjustment(const std::vector<cv::Mat>& grey,
                                                  const std::map<int, Pose>& initial,
                                                  const camera::CameraModel& camera,
                                                  const OfflineBaOptions& options) {
  auto pinhole = PinholeOf(camera);
  if (!pinhole) return Error{"OfflineBundleAdjustment " + pinhole.error()};
  if (initial.size() < 3) return Error{"OfflineBundleAdjustment: fewer than 3 initial poses"};
  const int first = initial.begin()->first, last = initial.rbegin()->first;
  if (first < 0 || last >= static_cast<int>(grey.size()) ||
      last - first + 1 != static_cast<int>(initial.size())) {
    return Error{"OfflineBundleAdjustment: the initial poses must be of consecutive frames " +
                 std::to_string(first) + ".." + std::to_string(last) + " of the sequence"};
  }
  Adjustment a;
  for (const auto& [frame, pose] : initial) a.cams[frame] = CameraFrom(pose);
  OfflineBaResult result;
  const std::vector<Track> tracks = TrackCorners(grey, first, last, options);
  result.tracks = static_cast<int>(tracks.size());
  for (const Track& track : tracks) {
    if (const auto x = Triangulate(track, a.cams, *pinhole, options)) {
      a.points.push_back(*x);
      a.tracks.push_back(&track);
    }
  }
  result.points = static_cast<int>(a.points.size());
  if (result.points < 20) return Error{"OfflineBundleAdjustment: too few tracks fit the poses"};
  const double baseline =
      (a.cams.rbegin()->second.Centre() - a.cams.begin()->second.Centre()).norm();
  Solve(1.0, baseline, *pinhole, &a);
  Solve(1.345 * ResidualSigma(a, *pinhole), baseline, *pinhole, &a);
  // σ of the residuals before pruning: measured again after each round it would shrink with the
  // tracks it drops, and the pruning would run away.
  const double sigma_px = ResidualSigma(a, *pinhole);
  for (int round = 0; round < options.prune_rounds; ++round) {
    PruneTracks(*pinhole, sigma_px, &a);
    if (a.points.size() < 20) return Error{"OfflineBundleAdjustment: pruning left too few tracks"};
    Solve(1.345 * sigma_px, baseline, *pinhole, &a);
  }
  result.points = static_cast<int>(a.points.size());
  result.residual_sigma_px = ResidualSigma(a, *pinhole);
  for (const auto& [frame, c] : a.cams) {
    result.world_from_cam[frame] = c.ToPose().Inverse();
  }
  return result;
}

}  // namespace rigcal::support
