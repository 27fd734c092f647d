// SPDX-License-Identifier: Apache-2.0
#pragma once
// A second reference for visp_rbt_sequence: the camera poses re-estimated from the detected
// tag corners together with where each tag really sits on the board.
//
// The recording's grid poses place the tags on an ideal flat grid. A printed board is not one:
// each tag is glued a little off, the board bends. Such a layout error is not random between
// frames; it moves the grid pose by a bias that changes slowly with the viewpoint, and the
// consistency of the single tags with the grid does not see it (every tag shares it). Here the
// poses of the camera in every frame and of every tag on the board are estimated jointly
// (bundle adjustment, Ceres): the corners of each tag are exact (the printed square of
// `tag_size`), the layout is whatever all frames together say. One tag is held fixed (the
// gauge); motions between frames do not depend on it.
//
// With the layout known, what remains is the corners' own detection noise. Its σ is measured
// from the residuals, and each frame's pose gets its Cramér-Rao bound: the covariance
// σ² (JᵀJ)⁻¹ of its six parameters with the layout held at its estimate.

#include <Eigen/Core>
#include <map>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "support/real_mono_sequence.h"

namespace rigcal::support {

struct RefinedTagGrid {
  // Per frame (the sequence's indices): the camera in the board's frame, Pose{q, C} like
  // RealMonoSequence::grid_from_cam.
  std::vector<Pose> grid_from_cam;
  // Each tag's pose on the board.
  std::map<int, Pose> grid_from_tag;
  // Per frame: the RMS distance between the detected corners and their projection, pixels.
  std::vector<double> residual_rms_px;
  // The same for the recording's own grid poses and layout (the ideal grid the tags' poses
  // imply, as TagGridResidualsPx), for comparison.
  std::vector<double> recorded_residual_rms_px;
  // Robust σ of one corner coordinate after the refinement (1.4826 MAD), pixels.
  double corner_sigma_px = 0.0;
  // Per frame: the Cramér-Rao σ of the camera's rotation about its own x, y, z axes, degrees.
  std::vector<Eigen::Vector3d> rotation_sigma_deg;
};

// Needs the sequence's tag detections and a pinhole camera without distortion (visp_rbt).
Expected<RefinedTagGrid> RefineTagGrid(const RealMonoSequence& sequence);

}  // namespace rigcal::support
