// MonocularVo initialisation: reference frame, two-view geometry, triangulation, first BA.

#include <algorithm>
#include <utility>
#include <vector>

#include "local_bundle_adjustment.h"
#include "monocular_vo_impl.h"
#include "relative_pose.h"
#include "rigcal/base/robust_statistics.h"
#include "triangulation.h"

namespace rigcal::vo {

void MonocularVo::Impl::StartReference(int64_t t_ns, const cv::Mat& grey) {
  tracks_.clear();
  has_reference_ = false;
  if (grey.empty()) return;
  AddNewTracks(grey, -1);
  if (static_cast<int>(tracks_.size()) >= options_.min_init_tracks) {
    has_reference_ = true;
    reference_t_ns_ = t_ns;
    state_ = VoState::kInitialising;
  } else {
    tracks_.clear();
  }
}

void MonocularVo::Impl::Initialise(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  result->state = state_;
  if (!has_reference_ || !klt_.has_previous()) {
    StartReference(t_ns, grey);
    result->state = state_;
    result->message = has_reference_ ? "reference frame set" : "too few features";
    return;
  }
  TrackFeatures(grey, nullptr);
  if (static_cast<int>(tracks_.size()) < options_.min_init_tracks) {
    StartReference(t_ns, grey);
    result->state = state_;
    result->message = "too few tracks to the reference frame; reference renewed";
    return;
  }

  const double threshold = options_.ransac_threshold_px * pixel_angle_;
  const double min_parallax = options_.min_init_parallax_deg * kDegToRad;
  std::vector<Eigen::Vector3d> f_ref, f_cur;
  f_ref.reserve(tracks_.size());
  f_cur.reserve(tracks_.size());
  for (const Track& t : tracks_) {
    f_ref.push_back(t.anchor_bearing);
    f_cur.push_back(t.bearing);
  }
  // Cheap test first: when a pure rotation explains the tracks to within a few pixels there is
  // no parallax to initialise from, whatever an essential matrix would say (with a pure
  // rotation every translation fits the epipolar constraint).
  auto rotation_residual = [&](const std::vector<char>* mask) {
    std::vector<Eigen::Vector3d> a, b;
    for (size_t i = 0; i < f_ref.size(); ++i) {
      if (mask != nullptr && !(*mask)[i]) continue;
      a.push_back(f_ref[i]);
      b.push_back(f_cur[i]);
    }
    const Eigen::Matrix3d r = BestRotation(a, b);
    std::vector<double> residual;
    residual.reserve(a.size());
    for (size_t i = 0; i < a.size(); ++i) residual.push_back(VectorAngle(a[i], r * b[i]));
    return UpperMedian(residual);
  };
  const double min_rotation_residual = options_.min_init_rotation_residual_px * pixel_angle_;
  if (rotation_residual(nullptr) < min_rotation_residual) {
    result->message = "insufficient parallax (rotation only)";
    return;
  }

  RelativePoseRansacOptions ransac;
  ransac.max_epipolar_angle_rad = threshold;
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.min_init_inliers;
  const RelativePoseRansacResult rel = EstimateRelativePose(f_ref, f_cur, ransac, &rng_);
  result->inliers = rel.num_inliers;
  if (!rel.success || rel.num_inliers < options_.min_init_inliers) {
    result->message = "essential matrix: too few inliers";
    return;
  }
  if (rel.num_in_front < options_.min_init_cheirality_fraction * rel.num_inliers) {
    result->message = "essential matrix: degenerate geometry (points behind the cameras)";
    return;
  }
  if (rotation_residual(&rel.inliers) < min_rotation_residual) {
    result->message = "insufficient parallax (rotation only)";
    return;
  }
  // Parallax: median angle between the rays of the inliers once the rotation is removed.
  std::vector<double> parallax;
  for (size_t i = 0; i < f_ref.size(); ++i) {
    if (rel.inliers[i]) parallax.push_back(VectorAngle(f_ref[i], rel.pose.R_1_from_2 * f_cur[i]));
  }
  const double median_parallax = UpperMedian(parallax);
  if (median_parallax < min_parallax) {
    result->message = "insufficient parallax";
    return;
  }

  // Triangulate the inliers in the reference frame, ||C^1|| = 1.
  const Eigen::Matrix3d& r1 = rel.pose.R_1_from_2;
  const Eigen::Vector3d c1 = rel.pose.C2_in_1.normalized();
  const double min_angle = options_.min_triangulation_angle_deg * kDegToRad;
  std::vector<std::pair<size_t, Eigen::Vector3d>> points;
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!rel.inliers[i]) continue;
    const auto tri = TriangulateMidpoint(Eigen::Vector3d::Zero(), f_ref[i], c1, r1 * f_cur[i]);
    if (!tri || tri->ray_angle_rad < min_angle) continue;
    if (BearingAngle(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), f_ref[i], tri->point) >
            2.0 * threshold ||
        BearingAngle(r1, c1, f_cur[i], tri->point) > 2.0 * threshold) {
      continue;
    }
    points.emplace_back(i, tri->point);
  }
  if (static_cast<int>(points.size()) < options_.min_init_inliers) {
    result->message = "too few triangulated points";
    return;
  }

  map_.Clear();
  const int kf0 =
      map_.AddKeyframe(reference_t_ns_, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  const int kf1 = map_.AddKeyframe(t_ns, Eigen::Quaterniond(r1), c1);
  for (Track& t : tracks_) t.anchor_keyframe = kf0;
  for (const auto& [i, point] : points) {
    const int lm = map_.AddLandmark(point);
    map_.AddObservation(lm, kf0, f_ref[i]);
    map_.AddObservation(lm, kf1, f_cur[i]);
    tracks_[i].landmark = lm;
  }
  LocalBaOptions ba;
  ba.num_fixed = 1;
  ba.unit_baseline = true;
  ba.max_iterations = std::max(10, options_.ba_max_iterations);
  ba.huber_rad = options_.ba_huber_px * pixel_angle_;
  ba.outlier_rad = 3.0 * threshold;
  LocalBundleAdjust({kf0, kf1}, ba, &map_);
  UnlinkRemovedLandmarks();
  const Keyframe* k1 = map_.keyframe(kf1);
  pose_.R_world_from_cam = k1->R();
  pose_.C = k1->C;
  has_velocity_ = false;
  last_keyframe_ = kf1;
  frames_since_keyframe_ = 0;
  keyframe_landmarks_ = 0;
  for (const Track& t : tracks_) keyframe_landmarks_ += t.landmark >= 0;
  if (keyframe_landmarks_ < options_.min_init_inliers / 2) {
    map_.Clear();
    for (Track& t : tracks_) {
      t.landmark = -1;
      t.anchor_keyframe = -1;
    }
    result->message = "initial bundle adjustment rejected the points";
    return;
  }
  AddNewTracks(grey, kf1);

  segment_ = next_segment_++;
  state_ = VoState::kTracking;
  const double quality = std::min(1.0, static_cast<double>(keyframe_landmarks_) / 100.0);
  result->state = state_;
  result->keyframe = true;
  result->message.clear();
  result->pose = MakePose(t_ns, pose_, quality);
  result->segment_start = MakePose(reference_t_ns_, CameraPoseRC{}, 1.0);
  log_->info("camera {}: initialised segment {} ({} points, {} inliers, parallax {:.2f} deg)",
             camera_index_, segment_, keyframe_landmarks_, rel.num_inliers,
             median_parallax / kDegToRad);
}

}  // namespace rigcal::vo
