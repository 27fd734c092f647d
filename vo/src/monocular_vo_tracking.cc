// MonocularVo tracking: PnP against the map, the keyframe decision, loss of tracking.

#include <algorithm>
#include <string>
#include <vector>

#include "monocular_vo_impl.h"
#include "rigcal/base/robust_statistics.h"
#include "triangulation.h"

namespace rigcal::vo {
namespace {

// Frame-to-frame motion of two poses (previous^-1 * current) and its application.
CameraPoseRC Between(const CameraPoseRC& a, const CameraPoseRC& b) {
  CameraPoseRC d;
  d.R_world_from_cam = a.R_world_from_cam.transpose() * b.R_world_from_cam;
  d.C = a.R_world_from_cam.transpose() * (b.C - a.C);
  return d;
}

CameraPoseRC Compose(const CameraPoseRC& a, const CameraPoseRC& d) {
  CameraPoseRC out;
  out.R_world_from_cam = a.R_world_from_cam * d.R_world_from_cam;
  out.C = a.C + a.R_world_from_cam * d.C;
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
  log_->warn("camera {}: tracking lost in segment {}: {}", camera_index_, segment_, reason);
  map_.Clear();
  tracks_.clear();
  has_velocity_ = false;
  has_reference_ = false;
  state_ = VoState::kLost;
  // The frame may still be good (e.g. a sudden motion): start the next reference from it.
  if (!grey.empty()) StartReference(t_ns, grey);
  if (!has_reference_) state_ = VoState::kLost;
  result->state = VoState::kLost;
  result->message = reason;
}

void MonocularVo::Impl::TrackFrame(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  const CameraPoseRC predicted = has_velocity_ ? Compose(pose_, velocity_) : pose_;
  TrackFeatures(grey, &predicted);
  ++frames_since_keyframe_;

  std::vector<int> index;
  std::vector<Eigen::Vector3d> f, X;
  for (int i = 0; i < static_cast<int>(tracks_.size()); ++i) {
    const Landmark* lm = tracks_[i].landmark >= 0 ? map_.landmark(tracks_[i].landmark) : nullptr;
    if (lm == nullptr) continue;
    index.push_back(i);
    f.push_back(tracks_[i].bearing);
    X.push_back(lm->point);
  }
  if (static_cast<int>(f.size()) < options_.min_tracking_inliers) {
    Lose("too few tracked map points (" + std::to_string(f.size()) + ")", t_ns, grey, result);
    return;
  }
  const double threshold = options_.ransac_threshold_px * pixel_angle_;
  PnpRansacOptions ransac;
  ransac.max_angle_rad = threshold;
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.min_tracking_inliers;
  PnpRansacResult pnp = EstimateAbsolutePose(f, X, ransac, &predicted, &rng_);
  const double ratio = pnp.success ? static_cast<double>(pnp.num_inliers) / f.size() : 0.0;
  if (!pnp.success || ratio < options_.min_inlier_ratio) {
    Lose("PnP: too few inliers (" + std::to_string(pnp.num_inliers) + " of " +
             std::to_string(f.size()) + ")",
         t_ns, grey, result);
    return;
  }
  CameraPoseRC pose = pnp.pose;
  if (!RefineAbsolutePose(f, X, pnp.inliers, options_.ba_huber_px * pixel_angle_, 10, &pose) ||
      !pose.R_world_from_cam.allFinite() || !pose.C.allFinite()) {
    Lose("PnP refinement failed (degenerate geometry)", t_ns, grey, result);
    return;
  }
  // Final inliers; outlier tracks are dropped (KLT drift or a bad point).
  std::vector<char> drop(tracks_.size(), 0);
  int inliers = 0;
  std::vector<double> parallax;
  const Keyframe* last_kf = map_.keyframe(last_keyframe_);
  for (size_t k = 0; k < f.size(); ++k) {
    if (AngularResidual(pose, f[k], X[k]) > threshold) {
      drop[index[k]] = 1;
      continue;
    }
    ++inliers;
    if (last_kf != nullptr) parallax.push_back(VectorAngle(X[k] - last_kf->C, X[k] - pose.C));
  }
  if (inliers < options_.min_tracking_inliers) {
    Lose("too few inliers after refinement (" + std::to_string(inliers) + ")", t_ns, grey, result);
    return;
  }
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!drop[i]) kept.push_back(tracks_[i]);
  }
  tracks_.swap(kept);

  velocity_ = Between(pose_, pose);
  has_velocity_ = true;
  pose_ = pose;

  // Keyframe decision.
  const double median_parallax = UpperMedian(parallax);
  const double kf_parallax = options_.keyframe_parallax_deg * kDegToRad;
  const bool need_keyframe = inliers < options_.keyframe_track_ratio * keyframe_landmarks_ ||
                             median_parallax >= kf_parallax ||
                             (frames_since_keyframe_ >= options_.keyframe_max_frames &&
                              median_parallax >= 0.5 * kf_parallax) ||
                             inliers < 2 * options_.min_tracking_inliers;
  if (need_keyframe) {
    CreateKeyframe(t_ns, grey);
    result->keyframe = true;
  }
  result->state = state_;
  result->inliers = inliers;
  const double quality = ratio * std::min(1.0, inliers / 100.0);
  result->pose = MakePose(t_ns, pose_, quality);
}

}  // namespace rigcal::vo
