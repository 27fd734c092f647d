// SPDX-License-Identifier: Apache-2.0
// MonocularVo initialisation: reference frame, two-view geometry, triangulation, first BA.
// Every threshold is a multiple of the measured track noise (monocular_vo_impl.h, gates).

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "local_bundle_adjustment.h"
#include "monocular_vo_impl.h"
#include "relative_pose.h"
#include "rigcal/base/robust_statistics.h"
#include "triangulation.h"

namespace rigcal::vo {
namespace {

// Median angle between the reference bearings and the current ones rotated by the best
// rotation (all tracks, or those with mask[i]), radians.
double RotationResidual(const InitialViews& views, const std::vector<char>* mask) {
  std::vector<Eigen::Vector3d> a, b;
  for (size_t i = 0; i < views.reference.size(); ++i) {
    if (mask != nullptr && !(*mask)[i]) continue;
    a.push_back(views.reference[i]);
    b.push_back(views.current[i]);
  }
  const Eigen::Matrix3d r = BestRotation(a, b);
  std::vector<double> residual;
  residual.reserve(a.size());
  for (size_t i = 0; i < a.size(); ++i) residual.push_back(VectorAngle(a[i], r * b[i]));
  return UpperMedian(residual);
}

}  // namespace

void MonocularVo::Impl::StartReference(int64_t t_ns, const cv::Mat& grey) {
  tracks_.clear();
  has_reference_ = false;
  rolling_shutter_.ClearMotion();  // BuildInitialMap corrects both views
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

bool MonocularVo::Impl::HasTranslation(const InitialViews& views, VoResult* result) const {
  // With a pure rotation every translation fits the epipolar constraint: no parallax to
  // initialise from, whatever an essential matrix would say.
  const double residual_rad = RotationResidual(views, nullptr);
  if (residual_rad > PairGateRad()) return true;
  result->message = fmt::format(
      "insufficient parallax (rotation only): median track {:.2f} px from the best rotation, "
      "gate {:.2f} px",
      residual_rad / pixel_angle_, PairGateRad() / pixel_angle_);
  return false;
}

bool MonocularVo::Impl::EstimateInitialMotion(const InitialViews& views,
                                              RelativePoseRansacResult* motion, VoResult* result) {
  RelativePoseRansacOptions ransac;
  ransac.max_epipolar_angle_rad = PairGateRad();
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.min_init_inliers;
  *motion = EstimateRelativePose(views.reference, views.current, ransac, &rng_);
  result->inliers = motion->num_inliers;
  // The epipolar distances of every track to the best model measure the noise the gates are
  // made of, also when the gate was too tight for enough inliers: the median of the distances
  // is robust to the tracks that do not fit (moving objects), and a gate set from the noise of
  // still frames opens once the hand-held camera moves and blurs.
  if (!motion->E.isZero()) {
    std::vector<double> distances_px;
    distances_px.reserve(views.reference.size());
    for (size_t i = 0; i < views.reference.size(); ++i) {
      distances_px.push_back(EpipolarAngle(motion->E, views.reference[i], views.current[i]) /
                             pixel_angle_);
    }
    noise_.AddEpipolarDistances(distances_px);
  }
  PreferPlanarMotion(views, motion, result);
  if (!motion->success || motion->num_inliers < options_.min_init_inliers) {
    result->message =
        fmt::format("essential matrix: too few inliers ({} of {}, gate {:.2f} px)",
                    motion->num_inliers, views.reference.size(), PairGateRad() / pixel_angle_);
    return false;
  }
  if (motion->num_in_front < options_.min_init_cheirality_fraction * motion->num_inliers) {
    result->message = fmt::format(
        "essential matrix: degenerate geometry ({} of {} inliers in front of the cameras)",
        motion->num_in_front, motion->num_inliers);
    return false;
  }
  if (RotationResidual(views, &motion->inliers) <= PairGateRad()) {
    result->message = "insufficient parallax (rotation only)";
    return false;
  }
  return true;
}

bool MonocularVo::Impl::HasInitialParallax(const InitialViews& views,
                                           const RelativePoseRansacResult& motion,
                                           VoResult* result) const {
  // The median angle between the rays of the inliers once the rotation is removed fixes their
  // depths to a relative σ of √2 σ_angle / parallax.
  std::vector<double> parallax;
  for (size_t i = 0; i < views.reference.size(); ++i) {
    if (motion.inliers[i]) {
      parallax.push_back(
          VectorAngle(views.reference[i], motion.pose.R_1_from_2 * views.current[i]));
    }
  }
  const double needed = std::max(options_.min_init_parallax_deg * kDegToRad,
                                 std::sqrt(2.0) * NoiseRad() / options_.init_depth_precision);
  const double median_rad = UpperMedian(parallax);
  if (median_rad >= needed) return true;
  result->message = fmt::format("insufficient parallax ({:.2f} deg of {:.2f} deg, {} inliers)",
                                median_rad / kDegToRad, needed / kDegToRad, motion.num_inliers);
  return false;
}

bool MonocularVo::Impl::BuildInitialMap(int64_t t_ns, const InitialViews& views,
                                        const RelativePoseRansacResult& motion, VoResult* result) {
  // Triangulate the inliers in the reference frame, ||C^1|| = 1.
  const Eigen::Matrix3d& r1 = motion.pose.R_1_from_2;
  const Eigen::Vector3d c1 = motion.pose.C2_in_1.normalized();
  const double min_angle = options_.min_triangulation_angle_deg * kDegToRad;
  const double gate = PoseGateRad();
  map_.Clear();
  const int kf0 =
      map_.AddKeyframe(reference_t_ns_, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  const int kf1 = map_.AddKeyframe(t_ns, Eigen::Quaterniond(r1), c1);
  const InitialViews corrected = ViewsAtStamps(t_ns, views, motion);
  for (size_t i = 0; i < tracks_.size(); ++i) {
    tracks_[i].anchor_keyframe = kf0;
    if (!motion.inliers[i]) continue;
    const Eigen::Vector3d& f0 = corrected.reference[i];
    const Eigen::Vector3d& f1 = corrected.current[i];
    tracks_[i].anchor_bearing = f0;
    tracks_[i].bearing = f1;
    const auto tri = TriangulateMidpoint(Eigen::Vector3d::Zero(), f0, c1, r1 * f1);
    if (!tri || tri->ray_angle_rad < min_angle ||
        BearingAngle(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), f0, tri->point) > gate ||
        BearingAngle(r1, c1, f1, tri->point) > gate) {
      continue;
    }
    const int lm = map_.AddLandmark(tri->point);
    map_.AddObservation(lm, kf0, f0);
    map_.AddObservation(lm, kf1, f1);
    tracks_[i].landmark = lm;
  }
  if (static_cast<int>(map_.landmarks().size()) < options_.min_init_inliers) {
    result->message = fmt::format("too few triangulated points ({} of {} inliers)",
                                  map_.landmarks().size(), motion.num_inliers);
  } else {
    LocalBaOptions ba;
    ba.num_fixed = 1;
    ba.unit_baseline = true;
    ba.max_iterations = std::max(10, options_.ba_max_iterations);
    ba.huber_rad = HuberRad();
    ba.outlier_rad = gate;
    LocalBundleAdjust({kf0, kf1}, ba, &map_);
    UnlinkRemovedLandmarks();
    keyframe_landmarks_ = 0;
    for (const Track& t : tracks_) keyframe_landmarks_ += t.landmark >= 0;
    if (keyframe_landmarks_ >= options_.min_init_inliers / 2) return true;
    result->message = "initial bundle adjustment rejected the points";
  }
  map_.Clear();
  // The tracks keep their views as measured: the next attempt corrects them with its motion.
  rolling_shutter_.ClearMotion();
  for (size_t i = 0; i < tracks_.size(); ++i) {
    tracks_[i].landmark = -1;
    tracks_[i].anchor_keyframe = -1;
    tracks_[i].anchor_bearing = views.reference[i];
    tracks_[i].bearing = views.current[i];
  }
  return false;
}

void MonocularVo::Impl::OpenSegment(int64_t t_ns, const cv::Mat& grey, int inliers,
                                    VoResult* result) {
  const int kf1 = map_.NewestKeyframes(1).front();
  const Keyframe* k1 = map_.keyframe(kf1);
  pose_.R_world_from_cam = k1->R();
  pose_.C = k1->C;
  pose_t_ns_ = t_ns;
  has_velocity_ = false;
  ResetRollingShutterPoses();
  RecordRollingShutterPose(reference_t_ns_, CameraPoseRC());
  RecordRollingShutterPose(t_ns, pose_);
  last_keyframe_ = kf1;
  frames_since_keyframe_ = 0;
  DescribeLandmarks(grey);
  AddNewTracks(grey, kf1);

  segment_ = next_segment_++;
  state_ = VoState::kTracking;
  lost_since_ns_ = -1;
  const double quality = std::min(1.0, static_cast<double>(keyframe_landmarks_) / 100.0);
  result->state = state_;
  result->keyframe = true;
  result->message.clear();
  result->pose = MakePose(t_ns, pose_, quality);
  result->segment_start = MakePose(reference_t_ns_, CameraPoseRC{}, 1.0);
  log_->info("camera {}: initialised segment {} ({} points, {} inliers, noise {:.2f} px)",
             camera_index_, segment_, keyframe_landmarks_, inliers, noise_.sigma_px());
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
  InitialViews views;
  for (const Track& t : tracks_) {
    views.reference.push_back(t.anchor_bearing);
    views.current.push_back(t.bearing);
  }
  RelativePoseRansacResult motion;
  if (!HasTranslation(views, result) || !EstimateInitialMotion(views, &motion, result) ||
      !HasInitialParallax(views, motion, result) || !BuildInitialMap(t_ns, views, motion, result)) {
    return;
  }
  OpenSegment(t_ns, grey, motion.num_inliers, result);
}

}  // namespace rigcal::vo
