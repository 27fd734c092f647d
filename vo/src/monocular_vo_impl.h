// SPDX-License-Identifier: Apache-2.0
#pragma once
// Private to vo/: the state of one camera's MonocularVo (MonocularVo::Impl) and its feature
// tracks. The stages are in monocular_vo_*.cc: setup, tracks, initialise, tracking, keyframe,
// relocalise.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "absolute_pose.h"
#include "affine_patch.h"
#include "exposure_compensation.h"
#include "feature_grid.h"
#include "frame_noise_reference.h"
#include "klt_tracker.h"
#include "map_descriptors.h"
#include "relative_pose.h"
#include "rigcal/base/logging.h"
#include "rigcal/vo/monocular_vo.h"
#include "rolling_shutter.h"
#include "track_noise.h"
#include "vo_map.h"

namespace rigcal::vo {

inline constexpr double kDegToRad = M_PI / 180.0;

// One KLT feature track.
struct Track {
  cv::Point2f px;
  Eigen::Vector3d bearing = Eigen::Vector3d::UnitZ();  // current frame, unit, camera frame
  // Rolling shutter: the observation is the ray ray_origin + s bearing (camera frame at the
  // stamp, ray_origin the camera centre at the row's time); 0 for a global shutter and for
  // tracks with a landmark, whose bearing is moved to the stamp at the landmark's distance.
  Eigen::Vector3d ray_origin = Eigen::Vector3d::Zero();
  int landmark = -1;  // map point, -1 = none yet
  // Where the track was born: a keyframe (tracking) or the reference frame (initialising,
  // anchor_keyframe = -1), and its bearing there (for triangulation and parallax).
  int anchor_keyframe = -1;
  Eigen::Vector3d anchor_bearing = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d anchor_ray_origin = Eigen::Vector3d::Zero();
  // Reference patch (affine refinement) and its current warp into the image; null: none.
  std::shared_ptr<const PatchTemplate> patch;
  Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();
};

// The tracks that see a landmark in the current frame: track index, bearing, landmark point.
struct MapMatches {
  std::vector<int> track;
  std::vector<Eigen::Vector3d> bearing;
  std::vector<Eigen::Vector3d> point;
  size_t size() const { return track.size(); }
};

// The landmarks a keyframe observes: track positions and landmark ids, to be described.
struct LandmarkViews {
  std::vector<cv::Point2f> px;
  std::vector<int> landmark;
};

// Keyframe work left to the start of the next frame (monocular_vo_deferred_keyframe.cc).
struct DeferredKeyframeWork {
  bool pending = false;
  int keyframe = -1;
  cv::Mat grey;  // the keyframe's image (a copy: the caller may reuse its buffer)
  LandmarkViews views;
};

// The bearings of the tracks to the reference frame of an initialisation.
struct InitialViews {
  std::vector<Eigen::Vector3d> reference;
  std::vector<Eigen::Vector3d> current;
};

class MonocularVo::Impl {
 public:
  // Checks `options` (InvalidOptions when invalid), then measures the lens: its valid image area,
  // field of view and feature budget (monocular_vo_setup.cc).
  Impl(std::shared_ptr<const camera::CameraModel> camera, int camera_index, VoOptions options);
  // One frame: initialisation, tracking or relocalisation, by state (monocular_vo.cc).
  VoResult Process(int64_t t_ns, const cv::Mat& image);

  VoState state_ = VoState::kInitialising;
  int segment_ = 0;
  int64_t frames_ = 0;
  int relocalisations_ = 0;
  VoOptions options_;
  double fov_sr_ = 0.0;  // solid angle of the valid image area
  int max_tracks_ = 0;   // feature budget for this lens

 private:
  // --- Feature tracks (monocular_vo_tracks.cc) ---
  // New tracks on free grid cells of `grey`, up to the feature budget, anchored at keyframe
  // `anchor_keyframe` (-1: the reference frame of an initialisation).
  void AddNewTracks(const cv::Mat& grey, int anchor_keyframe);
  // KLT of every track into `grey` (guided by the landmarks' projections at `predicted` when
  // not null), refined by RefineTrack; tracks that leave the valid area are dropped. Feeds the
  // forward-backward errors to the noise estimate.
  void TrackFeatures(const cv::Mat& grey, const CameraPoseRC* predicted);
  // Refines the KLT position of `track` by aligning its reference patch (affine) in `grey`;
  // renews the patch where it cannot be aligned or has deformed too much.
  void RefineTrack(const cv::Mat& grey, Track* track) const;
  std::shared_ptr<const PatchTemplate> MakePatch(const cv::Mat& grey, const cv::Point2f& px) const;
  // Keeps the tracks with keep[i] != 0.
  void KeepTracks(const std::vector<char>& keep);

  // --- Initialisation (monocular_vo_initialise.cc) ---
  // Makes `grey` the reference frame when it has enough features.
  void StartReference(int64_t t_ns, const cv::Mat& grey);
  // Two-view initialisation against the reference frame: opens a segment when it succeeds.
  void Initialise(int64_t t_ns, const cv::Mat& grey, VoResult* result);
  // False (and the reason in *result) while a pure rotation explains the median track.
  bool HasTranslation(const InitialViews& views, VoResult* result) const;
  // The essential matrix of the two views (RANSAC, refined, gates from the measured noise);
  // updates the noise from its epipolar distances. False (and why) when it fails.
  bool EstimateInitialMotion(const InitialViews& views, RelativePoseRansacResult* motion,
                             VoResult* result);
  // Fits a homography to the views too; when it explains them better than the essential
  // matrix of *motion (a plane, no depth variation within the noise), *motion becomes the
  // motion of its decomposition whose epipolar geometry the tracks support in front of both
  // views (monocular_vo_planar_init.cc). Without one such decomposition *motion is kept.
  void PreferPlanarMotion(const InitialViews& views, RelativePoseRansacResult* motion,
                          VoResult* result);
  // False (and why) while the inliers' parallax does not fix their depths.
  bool HasInitialParallax(const InitialViews& views, const RelativePoseRansacResult& motion,
                          VoResult* result) const;
  // The first keyframes and landmarks (||C^1|| = 1) and their bundle adjustment; false (map
  // cleared) when too few points survive.
  bool BuildInitialMap(int64_t t_ns, const InitialViews& views,
                       const RelativePoseRansacResult& motion, VoResult* result);
  // Opens the new segment at the second keyframe.
  void OpenSegment(int64_t t_ns, const cv::Mat& grey, int inliers, VoResult* result);

  // --- Tracking and loss (monocular_vo_tracking.cc) ---
  // PnP of the tracked landmarks, the keyframe decision, the pose of the frame.
  void TrackFrame(int64_t t_ns, const cv::Mat& grey, VoResult* result);
  // The pose at `t_ns` from the last motion (constant velocity, scaled to the time step).
  CameraPoseRC PredictPose(int64_t t_ns) const;

  // --- Rolling shutter (monocular_vo_rolling_shutter.cc); no-ops for a global shutter ---
  // The motion over this frame's readout: the twist of the motion across the recorded poses
  // (up to kRollingShutterWindow frame steps), in the camera at `predicted` (the frame's
  // predicted pose); with fewer than two poses the last motion is kept.
  void SetRollingShutterMotion(const CameraPoseRC& predicted);
  // Records the pose of the frame at t_ns for SetRollingShutterMotion; Reset: none yet (a new
  // segment, a loss). With fewer than two poses the last motion stays in use.
  void RecordRollingShutterPose(int64_t t_ns, const CameraPoseRC& pose);
  void ResetRollingShutterPoses();
  // The initialisation's views moved to their frames' stamps with the twist of its motion (the
  // two frames' rays triangulated); sets that twist for the current frame. `views` unchanged
  // for a global shutter. The tracks are not changed.
  InitialViews ViewsAtStamps(int64_t t_ns, const InitialViews& views,
                             const RelativePoseRansacResult& motion);
  // Moves every track's observation from its row's time to the stamp: bearings of map points at
  // their distance from `predicted`, rays for the others (Track::ray_origin).
  void CorrectTracksToStamp(const CameraPoseRC& predicted);
  // A track born or without a landmark: its ray at the stamp from its raw bearing.
  void SetRayAtStamp(Track* track) const;
  // The pixel where the camera sees the point `p_in_stamp_cam` (camera frame at the stamp),
  // the rolling shutter's motion included.
  std::optional<Eigen::Vector2d> ProjectFromStamp(const Eigen::Vector3d& p_in_stamp_cam) const;
  MapMatches CollectMapMatches() const;
  // PnP RANSAC + refinement of `matches`; updates the noise from the residuals. False when no
  // pose is found.
  bool EstimateFramePose(const MapMatches& matches, const CameraPoseRC& predicted,
                         CameraPoseRC* pose);
  // Classifies the tracks under `pose`: map matches within the pose gate are inliers (their
  // number is returned, their rotation-free angles to the last keyframe go to *parallax), those
  // within the two-view gate keep their landmark (counted in *linked), the others lose it;
  // tracks without a landmark that contradict their anchor's epipolar geometry (moving
  // objects, KLT slips) are dropped. The inliers' pixels go to *inlier_px.
  int ClassifyTracks(const MapMatches& matches, const CameraPoseRC& pose,
                     std::vector<double>* parallax, int* linked,
                     std::vector<Eigen::Vector2f>* inlier_px);
  bool NeedKeyframe(int inliers, int linked, const std::vector<double>& parallax) const;
  // Tracking failed: starts relocalising against the map (at once with `grey` if not empty).
  void Lose(const std::string& reason, int64_t t_ns, const cv::Mat& grey, VoResult* result);
  // Tracks whose landmark was removed from the map lose it.
  void UnlinkRemovedLandmarks();

  // --- Relocalisation (monocular_vo_relocalise.cc) ---
  // One attempt to find the pose of `grey` in the map; after relocalisation_timeout_s of
  // failures the map is dropped and a new initialisation starts.
  void Relocalise(int64_t t_ns, const cv::Mat& grey, VoResult* result);
  // The map's landmark descriptors.
  std::vector<LandmarkDescriptor> MapDescriptors() const;
  // Tracks for the relocalisation's inliers (placed on their landmarks' patches), the pose
  // refined on them, then a keyframe; the pose is reported.
  void ResumeTracking(int64_t t_ns, const cv::Mat& grey, const std::vector<OrbFeature>& features,
                      const std::vector<DescriptorMatch>& matches, const std::vector<char>& inliers,
                      CameraPoseRC pose, VoResult* result);
  // Aligns the landmark's reference patch at the track's ORB position (found at pyramid level
  // `octave`); on success the track takes the aligned position, the patch and its warp.
  bool PlaceOnLandmarkPatch(const cv::Mat& grey, const Landmark& landmark, int octave,
                            Track* track) const;
  // Relocalisation failed for too long: the map is dropped, the next initialisation opens a
  // new segment.
  void GiveUpSegment(int64_t t_ns, const cv::Mat& grey, VoResult* result);

  // --- Keyframes and local bundle adjustment (monocular_vo_keyframe.cc) ---
  void CreateKeyframe(int64_t t_ns, const cv::Mat& grey);
  // New landmarks from the tracks without one (anchor keyframe to keyframe `kf`).
  void TriangulateTracks(int kf);
  // Descriptors of the landmarks that the keyframe with image `grey` observes.
  void DescribeLandmarks(const cv::Mat& grey);
  // The landmarks the tracks observe now; hands the tracks' patches to their landmarks.
  LandmarkViews CollectLandmarkViews();
  // Adds the descriptors of `views` in `grey` to their landmarks (those still in the map).
  void AddLandmarkDescriptors(const cv::Mat& grey, const LandmarkViews& views);

  // --- Keyframe work spread over two frames (monocular_vo_deferred_keyframe.cc) ---
  // A keyframe frame runs the bundle adjustment; the landmarks' descriptors and the new tracks
  // of keyframe `kf` (image `grey`) are left to the next Process call, which does them first,
  // on the keyframe's image and before anything else changes: the same results, and a
  // keyframe frame costs about as much less as the next one costs more.
  void DeferKeyframeWork(const cv::Mat& grey, int kf);
  // Does the deferred work, if any.
  void FinishKeyframeWork();

  // --- Helpers (monocular_vo.cc, monocular_vo_setup.cc) ---
  CameraPose MakePose(int64_t t_ns, const CameraPoseRC& pose, double quality) const;
  bool Unproject(const cv::Point2f& px, Eigen::Vector3d* bearing) const;
  bool InMask(const cv::Point2f& px) const;
  // Gates, radians: a 2-D residual of one view (PnP, triangulation), one involving both views'
  // noise (epipolar distance, rotation residual), and the bundle adjustment's Huber scale.
  double PoseGateRad() const;
  double PairGateRad() const;
  double HuberRad() const;
  // The measured noise as an angle, radians.
  double NoiseRad() const;

  std::shared_ptr<const camera::CameraModel> camera_;
  int camera_index_ = 0;
  RollingShutter rolling_shutter_;  // the camera's readout; off for a global shutter
  // The last poses (ring, oldest at rs_next_ once full) and their stamps. The twist over the
  // readout comes from the motion across all of them: every pose is estimated with the twist
  // of the poses before it, so a short window feeds each pose's error into the next
  // correction, a long one lags the motion. Measured (docs/evaluations.md, VO robustness
  // matrix, 30 ms readout): 1 step 0.0188 deg frame-to-frame rotation RMS, 2 steps 0.0125,
  // 4 steps 0.0137, 8 steps 0.0307.
  static constexpr int kRollingShutterWindow = 2;
  std::array<CameraPoseRC, kRollingShutterWindow + 1> rs_poses_;
  std::array<int64_t, kRollingShutterWindow + 1> rs_t_ns_{};
  int rs_count_ = 0;
  int rs_next_ = 0;
  std::shared_ptr<spdlog::logger> log_;
  double pixel_angle_ = 1e-3;
  cv::Mat valid_mask_;  // CV_8UC1: where tracks may live
  KltTracker klt_;
  ExposureCompensation exposure_;
  std::unique_ptr<FeatureGrid> grid_;
  std::unique_ptr<OrbDescriber> describer_;
  TrackNoise noise_;
  FrameNoiseReference usual_noise_;
  std::mt19937 rng_;

  std::vector<Track> tracks_;
  int next_segment_ = 0;

  // Initialisation.
  bool has_reference_ = false;
  int64_t reference_t_ns_ = 0;

  // Tracking.
  VoMap map_;
  CameraPoseRC pose_;
  int64_t pose_t_ns_ = 0;
  CameraPoseRC velocity_;       // last frame-to-frame motion ...
  int64_t velocity_dt_ns_ = 0;  // ... over this time
  bool has_velocity_ = false;
  int last_keyframe_ = -1;
  int frames_since_keyframe_ = 0;
  int keyframe_landmarks_ = 0;
  // The last tracked frame's factor in the pose quality (FrameNoiseReference::Add).
  double frame_noise_factor_ = 1.0;

  // Relocalisation: stream time of the first failed attempt of the current loss (-1: none).
  int64_t lost_since_ns_ = -1;

  DeferredKeyframeWork deferred_;
};

}  // namespace rigcal::vo
