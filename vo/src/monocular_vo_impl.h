#pragma once
// Private to vo/: the state of one camera's MonocularVo (MonocularVo::Impl) and its feature
// tracks. The stages are in monocular_vo_*.cc: setup, tracks, initialise, tracking, keyframe.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "absolute_pose.h"
#include "affine_patch.h"
#include "feature_grid.h"
#include "klt_tracker.h"
#include "rigcal/base/logging.h"
#include "rigcal/vo/monocular_vo.h"
#include "vo_map.h"

namespace rigcal::vo {

inline constexpr double kDegToRad = M_PI / 180.0;

// One KLT feature track.
struct Track {
  cv::Point2f px;
  Eigen::Vector3d bearing = Eigen::Vector3d::UnitZ();  // current frame, unit, camera frame
  int landmark = -1;                                   // map point, -1 = none yet
  // Where the track was born: a keyframe (tracking) or the reference frame (initialising,
  // anchor_keyframe = -1), and its bearing there (for triangulation and parallax).
  int anchor_keyframe = -1;
  Eigen::Vector3d anchor_bearing = Eigen::Vector3d::UnitZ();
  // Reference patch (affine refinement) and its current warp into the image; null: none.
  std::shared_ptr<const PatchTemplate> patch;
  Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();
};

class MonocularVo::Impl {
 public:
  // Checks `options` (InvalidOptions when invalid), then measures the lens: its valid image area,
  // field of view and feature budget (monocular_vo_setup.cc).
  Impl(std::shared_ptr<const camera::CameraModel> camera, int camera_index, VoOptions options);
  // One frame: initialisation or tracking, by state (monocular_vo.cc).
  VoResult Process(int64_t t_ns, const cv::Mat& image);

  VoState state_ = VoState::kInitialising;
  int segment_ = 0;
  int64_t frames_ = 0;
  VoOptions options_;
  double fov_sr_ = 0.0;  // solid angle of the valid image area
  int max_tracks_ = 0;   // feature budget for this lens

 private:
  // --- Feature tracks (monocular_vo_tracks.cc) ---
  // New tracks on free grid cells of `grey`, up to the feature budget, anchored at keyframe
  // `anchor_keyframe` (-1: the reference frame of an initialisation).
  void AddNewTracks(const cv::Mat& grey, int anchor_keyframe);
  // KLT of every track into `grey` (guided by the landmarks' projections at `predicted` when
  // not null), refined by RefineTrack; tracks that leave the valid area are dropped.
  void TrackFeatures(const cv::Mat& grey, const CameraPoseRC* predicted);
  // Refines the KLT position of `track` by aligning its reference patch (affine) in `grey`;
  // renews the patch where it cannot be aligned or has deformed too much.
  void RefineTrack(const cv::Mat& grey, Track* track) const;
  std::shared_ptr<const PatchTemplate> MakePatch(const cv::Mat& grey, const cv::Point2f& px) const;

  // --- Initialisation (monocular_vo_initialise.cc) ---
  // Makes `grey` the reference frame when it has enough features.
  void StartReference(int64_t t_ns, const cv::Mat& grey);
  // Two-view initialisation against the reference frame: opens a segment when it succeeds.
  void Initialise(int64_t t_ns, const cv::Mat& grey, VoResult* result);

  // --- Tracking and loss (monocular_vo_tracking.cc) ---
  // PnP of the tracked landmarks, the keyframe decision, the pose of the frame.
  void TrackFrame(int64_t t_ns, const cv::Mat& grey, VoResult* result);
  // Tracking failed: clears the map and starts a new reference from `grey` (if not empty).
  void Lose(const std::string& reason, int64_t t_ns, const cv::Mat& grey, VoResult* result);
  // Tracks whose landmark was removed from the map lose it.
  void UnlinkRemovedLandmarks();

  // --- Keyframes and local bundle adjustment (monocular_vo_keyframe.cc) ---
  void CreateKeyframe(int64_t t_ns, const cv::Mat& grey);

  // --- Helpers (monocular_vo.cc, monocular_vo_setup.cc) ---
  CameraPose MakePose(int64_t t_ns, const CameraPoseRC& pose, double quality) const;
  bool Unproject(const cv::Point2f& px, Eigen::Vector3d* bearing) const;
  bool InMask(const cv::Point2f& px) const;

  std::shared_ptr<const camera::CameraModel> camera_;
  int camera_index_ = 0;
  std::shared_ptr<spdlog::logger> log_;
  double pixel_angle_ = 1e-3;
  cv::Mat valid_mask_;  // CV_8UC1: where tracks may live
  KltTracker klt_;
  std::unique_ptr<FeatureGrid> grid_;
  std::mt19937 rng_;

  std::vector<Track> tracks_;
  int next_segment_ = 0;

  // Initialisation.
  bool has_reference_ = false;
  int64_t reference_t_ns_ = 0;

  // Tracking.
  VoMap map_;
  CameraPoseRC pose_;
  CameraPoseRC velocity_;  // last frame-to-frame motion
  bool has_velocity_ = false;
  int last_keyframe_ = -1;
  int frames_since_keyframe_ = 0;
  int keyframe_landmarks_ = 0;
};

}  // namespace rigcal::vo
