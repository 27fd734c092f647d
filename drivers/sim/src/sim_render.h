// SPDX-License-Identifier: Apache-2.0
#pragma once
// Renderer of the simulated rig: per-camera bearing tables and ray-casting node grids, and the
// rendering of one view of the scene (ray casting at the nodes, texture blocks between them).
// Private to rigcal_sim.

#include <functional>
#include <memory>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/camera/camera_model.h"
#include "sim_scene.h"

namespace rigcal::sim::internal {

// Per camera: the unit bearing of every pixel (camera frame, NaN x when the pixel has none)
// and the local pixel angle, computed once.
struct CameraTables {
  std::shared_ptr<const camera::CameraModel> model;
  int width = 0;
  int height = 0;
  std::vector<float> bearings;  // 3 per pixel, row-major
  float max_axis_angle = 0.f;   // largest angle of a bearing from the optical axis, radians
};
CameraTables MakeCameraTables(std::shared_ptr<const camera::CameraModel> model);

// Ray-casting nodes every `block` pixels (block >= 2): node (i, j) sits at pixel
// (i * block, j * block); nodes just beyond the right/bottom edge close the last blocks.
struct NodeGrid {
  int block = 0;
  int nodes_x = 0;
  int nodes_y = 0;
  std::vector<float> bearings;     // 3 per node, NaN x when invalid
  std::vector<float> pixel_angle;  // per node, radians per pixel
  float max_axis_angle = 0.f;      // largest angle of a node's bearing from the optical axis
};
NodeGrid MakeNodeGrid(const CameraTables& camera, int block);

// Renders the view of `camera` at world_from_camera and adds weight * intensity to acc
// (width * height floats). `grid` null or block < 2: every pixel is cast. `hits`: scratch.
// `kernel`: the texture-block kernels to use. `moving`: null (the static scene), or the centres
// of the scene's moving boxes at the view's time (Scene::Cast).
void RenderAccumulate(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                      const Pose& world_from_camera, float weight, float* acc,
                      std::vector<Hit>* hits, RenderKernel kernel, const float* moving = nullptr);

// world_from_camera while the camera exposes image row `row` (0 = top). Rows up to the node
// grid's last row are asked for, which may lie one block beyond the image's last row.
using RowPose = std::function<Pose(int row)>;
// Writes the centres of the scene's moving boxes while image row `row` is exposed into
// `centres` (3 floats per box, Scene::Cast); asked for the same rows as a RowPose.
using RowMoving = std::function<void(int row, float* centres)>;

// As above for a rolling shutter: every pixel row is cast from its own row's pose, and each
// node row of the grid from the pose of the pixel row it sits on, so that texture coordinates
// inside a block are interpolated between the poses of its top and bottom rows (no seams
// between bands). The row poses are evaluated once per row, not per pixel. `moving_at_row`:
// empty (the static scene), or where the moving boxes are while each row is exposed (likewise
// once per row).
void RenderAccumulateRows(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                          const RowPose& world_from_camera_at_row, float weight, float* acc,
                          std::vector<Hit>* hits, RenderKernel kernel,
                          const RowMoving& moving_at_row = {});

}  // namespace rigcal::sim::internal
