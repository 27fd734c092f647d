// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the images themselves say about a camera's motion, as well as any monocular method
// could: dense KLT tracks through a whole sequence, triangulated at a set of initial poses and
// adjusted jointly with every pose (offline, non-causal bundle adjustment with Ceres). A peer
// for the VO's evaluations on real frames: where this estimate and a reference disagree by more
// than both their noise, the images (under the camera model and a rigid scene) and the
// reference disagree, and no VO can come closer to the reference than that.
//
// Tracks: Shi-Tomasi corners, kept at `max_corners` per frame, tracked frame to frame by
// pyramidal KLT with a forward-backward check. A track enters the adjustment when it has at
// least `min_observations` frames, its rays at the initial poses open by at least
// `min_ray_angle_deg`, and it reprojects within `initial_gate_px` at every initial pose: a
// track on a moving object, a reflection or an occlusion edge does not fit the poses. The
// adjustment: the first frame's pose held fixed and the distance from the first to the last
// camera held at the initial poses' (the gauge), Huber-robust pixel residuals at 1.345 σ of
// the residuals of a first solve.

#include <map>
#include <opencv2/core.hpp>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::support {

struct OfflineBaOptions {
  int max_corners = 1000;
  double max_fb_error_px = 0.3;
  int min_observations = 8;
  double min_ray_angle_deg = 1.0;
  double initial_gate_px = 3.0;
  // Rounds of track pruning after the adjustment (0: none). Each round drops every track whose
  // RMS residual (per image axis, over its whole life) is above twice the robust σ of all
  // residuals, and adjusts again: a track that slips or sits on something that moves fits no
  // rigid scene over its life, though each of its residuals may look ordinary. (A χ² test of
  // each track at σ would take its residuals as independent; a KLT track's errors are not, they
  // add up along it, and such a test prunes nearly every long track.)
  int prune_rounds = 0;
};

struct OfflineBaResult {
  std::map<int, Pose> world_from_cam;  // every frame of `initial`, in its frame and scale
  int tracks = 0;                      // KLT tracks found
  int points = 0;                      // tracks in the adjustment (after pruning)
  double residual_sigma_px = 0.0;      // robust σ of one pixel coordinate at the solution
};

// `grey`: the frames (CV_8UC1); `initial`: world_from_cam of consecutive frames first..last
// (at least 3); `camera`: a pinhole without distortion (support/pinhole_intrinsics.h).
Expected<OfflineBaResult> OfflineBundleAdjustment(const std::vector<cv::Mat>& grey,
                                                  const std::map<int, Pose>& initial,
                                                  const camera::CameraModel& camera,
                                                  const OfflineBaOptions& options = {});

}  // namespace rigcal::support
