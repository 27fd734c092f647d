// MonocularVo keyframes: new landmarks by triangulation, windowed local bundle adjustment.

#include <algorithm>
#include <unordered_set>
#include <vector>

#include "local_bundle_adjustment.h"
#include "monocular_vo_impl.h"
#include "triangulation.h"

namespace rigcal::vo {

void MonocularVo::Impl::CreateKeyframe(int64_t t_ns, const cv::Mat& grey) {
  const int kf = map_.AddKeyframe(t_ns, Eigen::Quaterniond(pose_.R_world_from_cam), pose_.C);
  const double threshold = options_.ransac_threshold_px * pixel_angle_;
  const double min_angle = options_.min_triangulation_angle_deg * kDegToRad;
  const Eigen::Matrix3d r = pose_.R_world_from_cam;
  for (Track& t : tracks_) {
    if (t.landmark >= 0 && map_.landmark(t.landmark) != nullptr) {
      map_.AddObservation(t.landmark, kf, t.bearing);
      continue;
    }
    t.landmark = -1;
    const Keyframe* anchor = map_.keyframe(t.anchor_keyframe);
    if (anchor == nullptr) {  // the anchor left the window: restart the track's baseline here
      t.anchor_keyframe = kf;
      t.anchor_bearing = t.bearing;
      continue;
    }
    const Eigen::Matrix3d ra = anchor->R();
    const auto tri = TriangulateMidpoint(anchor->C, ra * t.anchor_bearing, pose_.C, r * t.bearing);
    if (!tri || tri->ray_angle_rad < min_angle) continue;
    if (BearingAngle(ra, anchor->C, t.anchor_bearing, tri->point) > 2.0 * threshold ||
        BearingAngle(r, pose_.C, t.bearing, tri->point) > 2.0 * threshold) {
      continue;
    }
    const int lm = map_.AddLandmark(tri->point);
    map_.AddObservation(lm, t.anchor_keyframe, t.anchor_bearing);
    map_.AddObservation(lm, kf, t.bearing);
    t.landmark = lm;
  }

  const std::vector<int> window = map_.NewestKeyframes(options_.ba_window);
  LocalBaOptions ba;
  ba.num_fixed = std::min<int>(2, static_cast<int>(window.size()) - 1);
  ba.max_iterations = options_.ba_max_iterations;
  ba.huber_rad = options_.ba_huber_px * pixel_angle_;
  ba.outlier_rad = 3.0 * threshold;
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
    }
  }
  AddNewTracks(grey, kf);
  last_keyframe_ = kf;
  frames_since_keyframe_ = 0;
  keyframe_landmarks_ = 0;
  for (const Track& t : tracks_) keyframe_landmarks_ += t.landmark >= 0;
}

}  // namespace rigcal::vo
