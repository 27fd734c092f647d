// SPDX-License-Identifier: Apache-2.0
// MonocularVo tracking: PnP against the map, the classification of the tracks, the keyframe
// decision, loss of tracking.

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "monocular_vo_impl.h"
#include "rigcal/base/robust_statistics.h"
#include "triangulation.h"

namespace rigcal::vo {
namespace {

// The motion from pose a to pose b (a^-1 b), and its application to a pose.
CameraPoseRC MotionBetween(const CameraPoseRC& a, const CameraPoseRC& b) {
  CameraPoseRC d;
  d.R_world_from_cam = a.R_world_from_cam.transpose() * b.R_world_from_cam;
  d.C = a.R_world_from_cam.transpose() * (b.C - a.C);
  return d;
}

CameraPoseRC ApplyMotion(const CameraPoseRC& a, const CameraPoseRC& d) {
  CameraPoseRC out;
  out.R_world_from_cam = a.R_world_from_cam * d.R_world_from_cam;
  out.C = a.C + a.R_world_from_cam * d.C;
  return out;
}

// A motion scaled in time: its rotation angle and translation times `factor`.
CameraPoseRC ScaleMotion(const CameraPoseRC& d, double factor) {
  const Eigen::AngleAxisd rotation(d.R_world_from_cam);
  CameraPoseRC out;
  out.R_world_from_cam = ExpSO3(rotation.axis() * rotation.angle() * factor);
  out.C = d.C * factor;
  return out;
}

}  // namespace

void MonocularVo::Impl::UnlinkRemovedLandmarks() {
  for (Track& t : tracks_) {
    if (t.landmark >= 0 && map_.landmark(t.landmark) == nullptr) t.landmark = -1;
  }
}

void MonocularVo::Impl::Lose(const std::string& reason, int64_t t_ns, const cv::Mat& grey,
                             VoResult* result) {
  log_->warn("camera {}: tracking lost in segment {}: {}; relocalising", camera_index_, segment_,
             reason);
  tracks_.clear();
  has_velocity_ = false;
  // No motion until two poses are tracked again: the relocalisation's frame is taken as is.
  ResetRollingShutterPoses();
  rolling_shutter_.ClearMotion();
  has_reference_ = false;
  state_ = VoState::kLost;
  lost_since_ns_ = -1;
  result->state = VoState::kLost;
  result->message = "tracking lost: " + reason;
  // The frame may still show the map (a jolt, a gap in the frames): relocalise at once.
  if (!grey.empty()) Relocalise(t_ns, grey, result);
}

CameraPoseRC MonocularVo::Impl::PredictPose(int64_t t_ns) const {
  if (!has_velocity_ || velocity_dt_ns_ <= 0) return pose_;
  const double factor = static_cast<double>(t_ns - pose_t_ns_) / velocity_dt_ns_;
  return ApplyMotion(pose_, ScaleMotion(velocity_, factor));
}

MapMatches MonocularVo::Impl::CollectMapMatches() const {
  MapMatches matches;
  for (int i = 0; i < static_cast<int>(tracks_.size()); ++i) {
    const Landmark* lm = tracks_[i].landmark >= 0 ? map_.landmark(tracks_[i].landmark) : nullptr;
    if (lm == nullptr) continue;
    matches.track.push_back(i);
    matches.bearing.push_back(tracks_[i].bearing);
    matches.point.push_back(lm->point);
  }
  return matches;
}

bool MonocularVo::Impl::EstimateFramePose(const MapMatches& matches, const CameraPoseRC& predicted,
                                          CameraPoseRC* pose) {
  PnpRansacOptions ransac;
  ransac.max_angle_rad = PoseGateRad();
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.min_tracking_inliers;
  const PnpRansacResult pnp =
      EstimateAbsolutePose(matches.bearing, matches.point, ransac, &predicted, &rng_);
  if (!pnp.success) return false;
  *pose = pnp.pose;
  if (!RefineAbsolutePose(matches.bearing, matches.point, pnp.inliers, HuberRad(), 10, pose)) {
    return false;
  }
  // Every match's residual measures the noise; the pose is refined again within the new gate.
  std::vector<double> residuals_px(matches.size());
  for (size_t k = 0; k < matches.size(); ++k) {
    residuals_px[k] = AngularResidual(*pose, matches.bearing[k], matches.point[k]) / pixel_angle_;
  }
  noise_.AddPoseResiduals(residuals_px);
  frame_noise_factor_ =
      usual_noise_.Add(TrackNoise::RobustSigma(residuals_px, 1.0, 2, options_.inlier_sigmas));
  const double gate_px = PoseGateRad() / pixel_angle_;
  std::vector<char> inliers(matches.size());
  for (size_t k = 0; k < matches.size(); ++k) inliers[k] = residuals_px[k] <= gate_px;
  return RefineAbsolutePose(matches.bearing, matches.point, inliers, HuberRad(), 10, pose) &&
         pose->R_world_from_cam.allFinite() && pose->C.allFinite();
}

int MonocularVo::Impl::ClassifyTracks(const MapMatches& matches, const CameraPoseRC& pose,
                                      std::vector<double>* parallax, int* linked,
                                      std::vector<Eigen::Vector2f>* inlier_px) {
  // A landmark's residual against a pose estimated from the others carries the track's noise,
  // the landmark's own position error (it was triangulated from tracks as noisy) and the
  // pose's: about twice the variance of the noise alone. Within the pose gate it is an inlier;
  // within the two-view gate it keeps its landmark; beyond it the landmark is wrong or the track
  // slipped, and the track is judged below as one without a map point.
  const double inlier_gate = PoseGateRad();
  const double link_gate = PairGateRad();
  const Keyframe* last_kf = map_.keyframe(last_keyframe_);
  int inliers = 0;
  *linked = 0;
  for (size_t k = 0; k < matches.size(); ++k) {
    const double residual = AngularResidual(pose, matches.bearing[k], matches.point[k]);
    if (residual > link_gate) {
      tracks_[matches.track[k]].landmark = -1;
      continue;
    }
    ++*linked;
    if (residual > inlier_gate) continue;
    ++inliers;
    const cv::Point2f& px = tracks_[matches.track[k]].px;
    inlier_px->emplace_back(px.x, px.y);
    if (last_kf != nullptr) {
      parallax->push_back(VectorAngle(matches.point[k] - last_kf->C, matches.point[k] - pose.C));
    }
  }
  // Tracks without a map point must stay on the epipolar plane of their anchor's ray and the
  // baseline: a moving object or a track that slipped to another corner leaves it.
  const double plane_gate = PairGateRad();
  std::vector<char> keep(tracks_.size(), 1);
  for (size_t i = 0; i < tracks_.size(); ++i) {
    const Track& t = tracks_[i];
    const Keyframe* anchor = t.landmark < 0 ? map_.keyframe(t.anchor_keyframe) : nullptr;
    if (anchor == nullptr) continue;
    const Eigen::Vector3d baseline = (pose.C + pose.R_world_from_cam * t.ray_origin) -
                                     (anchor->C + anchor->R() * t.anchor_ray_origin);
    const Eigen::Vector3d normal = baseline.cross(anchor->R() * t.anchor_bearing);
    if (normal.norm() < 1e-12) continue;  // no baseline yet
    const double off_plane = std::asin(
        std::min(1.0, std::abs(normal.normalized().dot(pose.R_world_from_cam * t.bearing))));
    keep[i] = off_plane <= plane_gate;
  }
  KeepTracks(keep);
  return inliers;
}

bool MonocularVo::Impl::NeedKeyframe(int inliers, int linked,
                                     const std::vector<double>& parallax) const {
  const double median_parallax = UpperMedian(parallax);
  const double kf_parallax = options_.keyframe_parallax_deg * kDegToRad;
  return linked < options_.keyframe_track_ratio * keyframe_landmarks_ ||
         median_parallax >= kf_parallax ||
         (frames_since_keyframe_ >= options_.keyframe_max_frames &&
          median_parallax >= 0.5 * kf_parallax) ||
         inliers < 2 * options_.min_tracking_inliers;
}

void MonocularVo::Impl::TrackFrame(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  const CameraPoseRC predicted = PredictPose(t_ns);
  SetRollingShutterMotion(predicted);
  TrackFeatures(grey, &predicted);
  CorrectTracksToStamp(predicted);
  ++frames_since_keyframe_;
  const MapMatches matches = CollectMapMatches();
  const std::string matched = std::to_string(matches.size());
  if (static_cast<int>(matches.size()) < options_.min_tracking_inliers) {
    Lose("too few tracked map points (" + matched + ")", t_ns, grey, result);
    return;
  }
  CameraPoseRC pose;
  if (!EstimateFramePose(matches, predicted, &pose)) {
    Lose("PnP: no pose from " + matched + " map points", t_ns, grey, result);
    return;
  }
  std::vector<double> parallax;
  int linked = 0;
  std::vector<Eigen::Vector2f> inlier_px;
  const int inliers = ClassifyTracks(matches, pose, &parallax, &linked, &inlier_px);
  if (inliers < options_.min_tracking_inliers ||
      inliers < options_.min_inlier_ratio * static_cast<double>(matches.size())) {
    Lose("PnP: too few inliers (" + std::to_string(inliers) + " of " + matched + ")", t_ns, grey,
         result);
    return;
  }
  velocity_ = MotionBetween(pose_, pose);
  velocity_dt_ns_ = t_ns - pose_t_ns_;
  has_velocity_ = true;
  pose_ = pose;
  pose_t_ns_ = t_ns;
  if (NeedKeyframe(inliers, linked, parallax)) {
    CreateKeyframe(t_ns, grey);
    result->keyframe = true;
  }
  RecordRollingShutterPose(t_ns, pose_);
  result->state = state_;
  result->inliers = inliers;
  result->inlier_px = std::move(inlier_px);
  // The pose quality: the inlier ratio, the inliers up to 100, and how the frame's track noise
  // compares with the camera's usual (FrameNoiseReference: blur, darkness, image noise).
  const double ratio = static_cast<double>(inliers) / static_cast<double>(matches.size());
  result->pose =
      MakePose(t_ns, pose_, ratio * std::min(1.0, inliers / 100.0) * frame_noise_factor_);
}

}  // namespace rigcal::vo
