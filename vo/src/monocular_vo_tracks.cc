// SPDX-License-Identifier: Apache-2.0
// MonocularVo feature tracks: detection, KLT tracking and affine patch refinement.

#include <Eigen/Core>
#include <cmath>

#include "monocular_vo_impl.h"

namespace rigcal::vo {

void MonocularVo::Impl::AddNewTracks(const cv::Mat& grey, int anchor_keyframe) {
  const int room = max_tracks_ - static_cast<int>(tracks_.size());
  if (room <= 0) return;
  std::vector<cv::Point2f> existing;
  existing.reserve(tracks_.size());
  for (const Track& t : tracks_) existing.push_back(t.px);
  for (const cv::Point2f& px : grid_->Detect(grey, existing, room)) {
    Track t;
    t.px = px;
    if (!Unproject(px, &t.bearing)) continue;
    SetRayAtStamp(&t);
    t.patch = MakePatch(grey, px);
    t.anchor_keyframe = anchor_keyframe;
    t.anchor_bearing = t.bearing;
    t.anchor_ray_origin = t.ray_origin;
    tracks_.push_back(t);
  }
}

std::shared_ptr<const PatchTemplate> MonocularVo::Impl::MakePatch(const cv::Mat& grey,
                                                                  const cv::Point2f& px) const {
  if (options_.affine_half_size <= 0) return nullptr;
  auto patch = std::make_shared<PatchTemplate>();
  if (!MakePatchTemplate(grey, px, options_.affine_half_size, patch.get())) return nullptr;
  return patch;
}

void MonocularVo::Impl::RefineTrack(const cv::Mat& grey, Track* track) const {
  if (options_.affine_half_size <= 0) return;
  if (track->patch != nullptr) {
    AffinePatchOptions affine;
    affine.half_size = options_.affine_half_size;
    Eigen::Matrix2d warp = track->warp;
    Eigen::Vector2d centre(track->px.x, track->px.y);
    if (AlignPatch(*track->patch, grey, affine, &warp, &centre) &&
        (centre - Eigen::Vector2d(track->px.x, track->px.y)).norm() <=
            options_.affine_max_shift_px) {
      track->px = cv::Point2f(static_cast<float>(centre.x()), static_cast<float>(centre.y()));
      track->warp = warp;
      // Keep the reference close to the current view: the patch is sampled anew once it
      // appears at a very different size or shape.
      const double area = warp.determinant();
      const double shear = (warp / std::sqrt(std::abs(area)) - Eigen::Matrix2d::Identity()).norm();
      if (area > options_.affine_min_area && area < 1.0 / options_.affine_min_area && shear < 0.4) {
        return;
      }
    }
  }
  track->patch = MakePatch(grey, track->px);
  track->warp.setIdentity();
}

void MonocularVo::Impl::KeepTracks(const std::vector<char>& keep) {
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (keep[i]) kept.push_back(std::move(tracks_[i]));
  }
  tracks_.swap(kept);
}

void MonocularVo::Impl::TrackFeatures(const cv::Mat& grey, const CameraPoseRC* predicted) {
  std::vector<cv::Point2f> previous, guesses, tracked;
  std::vector<unsigned char> ok;
  previous.reserve(tracks_.size());
  for (const Track& t : tracks_) previous.push_back(t.px);
  guesses = previous;
  if (predicted != nullptr) {
    const Eigen::Matrix3d rt = predicted->R_world_from_cam.transpose();
    for (size_t i = 0; i < tracks_.size(); ++i) {
      const Landmark* lm = tracks_[i].landmark >= 0 ? map_.landmark(tracks_[i].landmark) : nullptr;
      if (lm == nullptr) continue;
      const auto px = ProjectFromStamp(rt * (lm->point - predicted->C));
      if (px.has_value() && px->allFinite()) {
        const cv::Point2f guess(static_cast<float>(px->x()), static_cast<float>(px->y()));
        if (InMask(guess)) guesses[i] = guess;
      }
    }
  }
  std::vector<double> fb_px;
  klt_.Track(previous, guesses, &tracked, &ok, &fb_px);
  noise_.AddForwardBackward(fb_px);
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!ok[i] || !InMask(tracked[i])) continue;
    Track t = tracks_[i];
    t.px = tracked[i];
    RefineTrack(grey, &t);
    if (!InMask(t.px) || !Unproject(t.px, &t.bearing)) continue;
    kept.push_back(t);
  }
  tracks_.swap(kept);
}

}  // namespace rigcal::vo
