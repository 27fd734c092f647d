// SPDX-License-Identifier: Apache-2.0
#pragma once
// MonocularVo: visual odometry of one camera (thesis 3.5, made robust). It turns a stream of
// grey images into the camera's poses T^k = [R^k | C^k] in its own reference frame (R^0 = I,
// C^0 = 0) and its own arbitrary unit (the first baseline has length 1), one scale segment at
// a time.
//
// Method (details in vo/src/):
//  - KLT pyramidal tracking (OpenCV) with a forward-backward check, refined by aligning each
//    track's reference patch with an affine warp (no drift where patches deform); new
//    features from FAST corners, at most one per grid cell, at keyframes.
//  - Initialisation: 5-point essential matrix in a RANSAC on unit bearing vectors (so it works
//    for lenses wider than 180 degrees), accepted only with enough parallax left after the
//    best pure rotation is removed; triangulation; two-view bundle adjustment; ||C^1|| = 1.
//  - Tracking: P3P RANSAC on bearings (angular residuals) + motion-only refinement; keyframes;
//    new points triangulated at keyframes; a windowed local bundle adjustment (Ceres).
//  - Gates from measured noise: σ of the track positions is measured on the images (KLT
//    forward-backward errors, epipolar and pose residuals) and every threshold is a multiple
//    of it, so real blurred frames and rendered ones share one set of options.
//  - Failure (too few inliers, degenerate geometry, blank images, a gap in the frames) ->
//    state kLost: the VO relocalises against its own map (ORB descriptors of the landmarks at
//    keyframes, P3P RANSAC) and goes on in the same scale segment; only when relocalisation
//    has failed for VoOptions::relocalisation_timeout_s does a new initialisation open a new
//    scale segment whose reference frame is again the identity.
//
// Thread: a MonocularVo is used by one thread at a time (the pipeline's VO thread of its
// camera); it starts no thread itself.

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::vo {

struct VoOptions {
  // --- Features and KLT ---
  // Image grid for feature replenishment: one feature per cell of this size, pixels.
  int grid_cell_px = 32;
  // Upper bound of tracked features of a lens whose field of view covers up to normal_fov_sr
  // steradians (2 sr: about 90 x 70 degrees). A wider lens (fisheye, catadioptric) tracks
  // max_features * Ω / normal_fov_sr for its field of view Ω (a 186-degree fisheye: 6.6 sr,
  // 3.3x), with the grid cells shrunk so that its valid area holds as many cells: its pixels
  // are ~3x coarser in angle, so with the normal count its pose is ~2x noisier (sewer rig of
  // thesis 5.6, rotation error over 20 frames front/rear: 0.037/0.056 deg with 150 features,
  // 0.018/0.034 deg with 496). normal_fov_sr = 0: max_features for every lens.
  int max_features = 150;
  double normal_fov_sr = 2.0;
  // FAST corner threshold (grey levels); lowered automatically in low-texture images.
  int fast_threshold = 20;
  // KLT window side, pixels (odd), and number of pyramid levels above the base image.
  int klt_window_px = 15;
  int klt_pyramid_levels = 2;
  // Forward-backward check: a track is dropped when tracking back lands farther than this
  // from where it started, pixels.
  double klt_max_fb_error_px = 0.5;
  // Features closer than this to the image border or to the edge of the lens's valid area
  // are not detected, pixels.
  int border_px = 12;
  // Affine refinement of every KLT track: the track's reference patch, (2 h + 1)^2 pixels
  // with h = affine_half_size, is aligned into each new image with an affine warp (0: off).
  // Frame-to-frame KLT alone drifts where patches deform (zoom, perspective, fisheye), which
  // biases triangulation and makes the scale drift. A refinement that moves the KLT position
  // by more than affine_max_shift_px is refused and the patch is sampled anew.
  // The patch is also sampled anew once the warp scales its area by less than
  // affine_min_area (a shrunk patch has lost detail its reference still has: the alignment
  // becomes biased quickly) or by more than affine_max_area (a grown one shows detail the
  // reference lacks, which biases it much less).
  int affine_half_size = 5;
  double affine_max_shift_px = 1.5;
  double affine_min_area = 0.9;
  double affine_max_area = 1.7;

  // --- Measurement noise and gates ---
  // The VO measures the per-axis standard deviation σ of its track positions in pixels of the
  // camera's centre resolution (KLT forward-backward errors, then the residuals of its own
  // epipolar geometry and poses; a running robust estimate over about noise_window_frames
  // frames, never below noise_floor_px). Every gate is inlier_sigmas σ: the inliers of the
  // essential matrix, of PnP and of triangulation, the observations the bundle adjustment
  // keeps (3.03: 99 % of a 2-D Gaussian error), and the Huber scale of the bundle adjustment is
  // huber_sigmas σ (1.345: 95 % efficiency on Gaussian errors). So the same options gate
  // rendered frames (σ ~0.05 px) and blurred real ones (σ ~0.3 px).
  double inlier_sigmas = 3.03;
  double huber_sigmas = 1.345;
  double noise_floor_px = 0.1;
  int noise_window_frames = 10;
  int ransac_max_iterations = 200;
  double ransac_confidence = 0.999;

  // --- Initialisation ---
  // Minimum tracks to the reference frame; below it the reference frame is renewed.
  int min_init_tracks = 60;
  // Minimum essential-matrix inliers and triangulated points to accept an initialisation.
  int min_init_inliers = 50;
  // The two views are accepted once the median angle between the rays of the inlier tracks
  // (the essential matrix's rotation removed) fixes the depths to init_depth_precision
  // (relative σ of a depth: √2 σ_angle / parallax, σ_angle the measured noise as an angle),
  // and is at least min_init_parallax_deg. They are not even tried while the best pure
  // rotation explains the median track within the noise gate: pure rotation or no motion never
  // produces a translation.
  double init_depth_precision = 0.05;
  double min_init_parallax_deg = 0.5;
  // Fraction of essential-matrix inliers that must triangulate in front of both views.
  double min_init_cheirality_fraction = 0.9;

  // --- Tracking ---
  // Fewer PnP inliers than this, or an inlier ratio below min_inlier_ratio -> lost.
  int min_tracking_inliers = 20;
  double min_inlier_ratio = 0.3;
  // Smallest angle between the two rays of a new triangulated point, degrees.
  double min_triangulation_angle_deg = 1.0;

  // --- Relocalisation ---
  // After a tracking loss (a gap in the frames, a covered lens, a jolt) the VO relocalises
  // against its map: ORB descriptors of the landmarks, taken at keyframes, are matched with
  // the ORB features of the new frame (at most relocalisation_features; a match's Hamming
  // distance within relocalisation_max_bits of 256, and below relocalisation_ratio times the
  // second best landmark's), then P3P RANSAC on bearings and a refinement; at least
  // relocalisation_min_inliers inliers continue the same scale segment. A new segment opens
  // only once relocalisation has failed for relocalisation_timeout_s of stream time (the log
  // says why).
  double relocalisation_timeout_s = 2.0;
  int relocalisation_features = 1000;
  int relocalisation_max_bits = 64;
  double relocalisation_ratio = 0.8;
  int relocalisation_min_inliers = 20;

  // --- Keyframes and local bundle adjustment ---
  // A new keyframe when the tracked map points fall below this fraction of those the last
  // keyframe saw, when the rotation-compensated parallax to it exceeds keyframe_parallax_deg,
  // or after keyframe_max_frames frames.
  double keyframe_track_ratio = 0.8;
  double keyframe_parallax_deg = 3.0;
  int keyframe_max_frames = 8;
  // Keyframes in the local bundle adjustment window (the two oldest are held fixed, which
  // fixes the gauge and the scale), and its iteration limit.
  int ba_window = 6;
  int ba_max_iterations = 5;

  // Seed of the RANSAC sampling (the VO is deterministic for a given input).
  uint32_t seed = 42;

  // Success, or the first offending field and its constraint: "<field>: <constraint>".
  Status Check() const;
};

enum class VoState {
  kInitialising,  // waiting for enough parallax to the reference frame
  kTracking,      // poses are reported
  kLost,          // tracking failed: relocalising (then, after the timeout, a new segment)
};

std::string ToString(VoState state);

// The outcome of one Process() call.
struct VoResult {
  // The camera's pose at this frame (camera-local reference frame and unit of its segment);
  // nullopt while initialising or lost.
  std::optional<CameraPose> pose;
  // Set on the frame that opens a segment (successful initialisation): the identity pose of
  // the segment's reference frame, whose t_ns is earlier than this frame's. A consumer that
  // wants every pose of the segment puts it before `pose`.
  std::optional<CameraPose> segment_start;
  VoState state = VoState::kInitialising;
  int tracked_features = 0;  // KLT tracks alive after this frame
  int inliers = 0;           // PnP (tracking) or essential-matrix (initialisation) inliers
  // A tracked frame: the image positions (pixels) of the tracks whose landmark is a pose
  // inlier, the `inliers` features its pose rests on (overlays, evaluations); empty otherwise
  // (initialising, lost, relocalised).
  std::vector<Eigen::Vector2f> inlier_px;
  bool keyframe = false;  // this frame became a keyframe
  // This frame's pose came from relocalising against the map after a loss (same segment).
  bool relocalised = false;
  // Relocalisations since the VO was made (all segments), this one included.
  int relocalisations = 0;
  // The measured per-axis noise of the track positions, pixels (see VoOptions::inlier_sigmas).
  double track_noise_px = 0.0;
  double processing_ms = 0.0;
  std::string message;  // why the VO is initialising or lost (empty when tracking)
};

class MonocularVo {
 public:
  // `camera` must not be null; `camera_index` is written into every CameraPose. Throws
  // InvalidOptions ("VoOptions: <field>: <constraint>") when options.Check() fails.
  MonocularVo(std::shared_ptr<const camera::CameraModel> camera, int camera_index,
              VoOptions options = {});
  ~MonocularVo();
  MonocularVo(const MonocularVo&) = delete;
  MonocularVo& operator=(const MonocularVo&) = delete;
  MonocularVo(MonocularVo&&) noexcept;
  MonocularVo& operator=(MonocularVo&&) noexcept;

  // Processes the next image of the camera, taken at `t_ns` (increasing). `grey` is CV_8UC1
  // (CV_8UC3/4 are converted) of the camera model's size; an empty or wrongly sized image
  // counts as a frame without features (never a crash). Not thread-safe: one thread at a
  // time.
  VoResult Process(int64_t t_ns, const cv::Mat& grey);

  // Current state, scale segment id (0 for the first; incremented by every initialisation
  // after relocalisation gave up), number of frames processed and of relocalisations.
  VoState state() const;
  int segment() const;
  int64_t frames_processed() const;
  int relocalisations() const;
  const VoOptions& options() const;
  // The camera's field of view (solid angle of its valid image area, steradians) and the
  // number of features tracked at most for it (see VoOptions::max_features).
  double field_of_view_sr() const;
  int feature_budget() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigcal::vo
