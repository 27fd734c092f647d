// SPDX-License-Identifier: Apache-2.0
// MonocularVo keyframes: new landmarks by triangulation, windowed local bundle adjustment,
// the landmarks' descriptors for relocalisation.

#include <algorithm>
#include <unordered_set>
#include <vector>

#include "local_bundle_adjustment.h"
#include "monocular_vo_impl.h"
#include "triangulation.h"

namespace rigcal::vo {

void MonocularVo::Impl::TriangulateTracks(int kf) {
  const double gate = PoseGateRad();
  const double min_angle = options_.min_triangulation_angle_deg * kDegToRad;
  const Eigen::Matrix3d r = pose_.R_world_from_cam;
  for (Track& t : tracks_) {
    if (t.landmark >= 0) continue;
    const Keyframe* anchor = map_.keyframe(t.anchor_keyframe);
    if (anchor == nullptr || t.anchor_keyframe == kf) continue;
    const Eigen::Matrix3d ra = anchor->R();
    // Rays from the cameras' centres at the rows' times (rolling shutter; else the centres).
    const Eigen::Vector3d anchor_origin = anchor->C + ra * t.anchor_ray_origin;
    const Eigen::Vector3d origin = pose_.C + r * t.ray_origin;
    const auto tri =
        TriangulateMidpoint(anchor_origin, ra * t.anchor_bearing, origin, r * t.bearing);
    if (!tri || tri->ray_angle_rad < min_angle ||
        BearingAngle(ra, anchor_origin, t.anchor_bearing, tri->point) > gate ||
        BearingAngle(r, origin, t.bearing, tri->point) > gate) {
      continue;
    }
    const int lm = map_.AddLandmark(tri->point);
    map_.AddObservation(lm, t.anchor_keyframe,
                        BearingFromStamp(t.anchor_ray_origin, t.anchor_bearing,
                                         ra.transpose() * (tri->point - anchor->C)));
    t.bearing = BearingFromStamp(t.ray_origin, t.bearing, r.transpose() * (tri->point - pose_.C));
    t.ray_origin.setZero();
    map_.AddObservation(lm, kf, t.bearing);
    t.landmark = lm;
  }
}

LandmarkViews MonocularVo::Impl::CollectLandmarkViews() {
  LandmarkViews views;
  for (const Track& t : tracks_) {
    Landmark* lm = t.landmark >= 0 ? map_.landmark(t.landmark) : nullptr;
    if (lm == nullptr) continue;
    views.px.push_back(t.px);
    views.landmark.push_back(t.landmark);
    if (t.patch != nullptr) {
      lm->patch = t.patch;
      lm->warp = t.warp;
    }
  }
  return views;
}

void MonocularVo::Impl::AddLandmarkDescriptors(const cv::Mat& grey, const LandmarkViews& views) {
  std::vector<Descriptor> descriptors;
  std::vector<char> ok;
  describer_->Describe(grey, views.px, &descriptors, &ok);
  for (size_t i = 0; i < views.px.size(); ++i) {
    Landmark* lm = map_.landmark(views.landmark[i]);
    if (ok[i] && lm != nullptr) lm->AddDescriptor(descriptors[i]);
  }
}

void MonocularVo::Impl::DescribeLandmarks(const cv::Mat& grey) {
  AddLandmarkDescriptors(grey, CollectLandmarkViews());
}

void MonocularVo::Impl::CreateKeyframe(int64_t t_ns, const cv::Mat& grey) {
  const int kf = map_.AddKeyframe(t_ns, Eigen::Quaterniond(pose_.R_world_from_cam), pose_.C);
  for (Track& t : tracks_) {
    if (t.landmark >= 0 && map_.landmark(t.landmark) != nullptr) {
      map_.AddObservation(t.landmark, kf, t.bearing);
    } else if (map_.keyframe(t.anchor_keyframe) == nullptr) {
      // No anchor (it left the window, or a relocalised track): the baseline starts here.
      t.landmark = -1;
      t.anchor_keyframe = kf;
      t.anchor_bearing = t.bearing;
      t.anchor_ray_origin = t.ray_origin;
    }
  }
  TriangulateTracks(kf);

  const std::vector<int> window = map_.NewestKeyframes(options_.ba_window);
  LocalBaOptions ba;
  ba.num_fixed = std::min<int>(2, static_cast<int>(window.size()) - 1);
  ba.max_iterations = options_.ba_max_iterations;
  ba.huber_rad = HuberRad();
  ba.outlier_rad = PoseGateRad();
  if (ba.max_iterations > 0) {
    const LocalBaSummary summary = LocalBundleAdjust(window, ba, &map_);
    if (summary.success) {
      const Keyframe* k = map_.keyframe(kf);
      pose_.R_world_from_cam = k->R();
      pose_.C = k->C;
    }
    UnlinkRemovedLandmarks();
  }

  std::unordered_set<int> alive;
  for (const Track& t : tracks_) {
    if (t.landmark >= 0) alive.insert(t.landmark);
  }
  map_.PruneKeyframes(options_.ba_window, [&](int id) { return alive.count(id) > 0; });
  for (Track& t : tracks_) {
    if (map_.keyframe(t.anchor_keyframe) == nullptr) {
      t.anchor_keyframe = kf;
      t.anchor_bearing = t.bearing;
      t.anchor_ray_origin = t.ray_origin;
    }
  }
  DeferKeyframeWork(grey, kf);
  last_keyframe_ = kf;
  frames_since_keyframe_ = 0;
  keyframe_landmarks_ = 0;
  for (const Track& t : tracks_) keyframe_landmarks_ += t.landmark >= 0;
}

}  // namespace rigcal::vo
