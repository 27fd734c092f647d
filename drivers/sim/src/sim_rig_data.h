// SPDX-License-Identifier: Apache-2.0
#pragma once
// The immutable data of a simulated rig, shared by the rig and its devices (scene, trajectory,
// render tables, noise table), and the production of its frames: rendering with motion blur,
// rolling shutter and moving objects, image noise, quantisation, drops and stamp jitter. Private to
// rigcal_sim.

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rigcal/base/types.h"
#include "rigcal/sim/simulated_rig.h"
#include "sim_moving_objects.h"
#include "sim_render.h"
#include "sim_scene.h"
#include "sim_trajectory.h"

namespace rigcal::sim::internal {

// Standard normal samples in the noise table (rows of image noise start at random offsets).
inline constexpr size_t kNoiseTableSize = 1 << 18;

struct SimulatedRigData {
  SimulatedRigSpec spec;
  int64_t num_frames = 0;
  Trajectory trajectory;
  Scene scene;
  MovingObjects moving;  // where the scene's moving boxes are when
  std::vector<CameraTables> cameras;
  std::vector<NodeGrid> grids;  // per camera, for spec.render_block (unused when 1)
  std::vector<float> noise;     // standard normal samples
  std::vector<std::optional<double>> fail_after_s;  // per camera

  // Stream time of frame k, seconds (frame 0 at 0).
  double StreamTime(int64_t k) const { return static_cast<double>(k) / spec.frame_rate_hz; }
  // Nominal stamp of frame k after frame 0's, nanoseconds.
  int64_t OffsetNs(int64_t k) const {
    return std::llround(static_cast<double>(k) * 1e9 / spec.frame_rate_hz);
  }
  // world_from_camera of `camera` at stream time t_s.
  Pose WorldFromCamera(int camera, double t_s) const {
    return trajectory.At(t_s) * spec.master_from_camera[camera];
  }
  // Time from a frame's stamp to the exposure of image row `row` of `camera`, seconds:
  // row / (height - 1) of spec.rolling_shutter_s (0 with a global shutter). Rows beyond the
  // last one (the node grid's closing row) continue the line.
  double RowDelay(int camera, int row) const;
  // Whether frame k of `camera` is dropped (spec.drop_probability).
  bool Dropped(int camera, int64_t k) const;
  // Whether frame k of `camera` is black (spec.blackout_s).
  bool Blackout(int camera, int64_t k) const;
  // Whether frame k of `camera` is in a blur burst (spec.blur_burst_s).
  bool BlurBurst(int camera, int64_t k) const;
  // The gain of frame k of `camera` (spec.exposure_steps; 1 when off).
  double Gain(int camera, int64_t k) const;
  // Stamp noise of frame k of `camera`, nanoseconds (spec.timestamp_jitter_s, clipped at 3 sigma).
  int64_t JitterNs(int camera, int64_t k) const;
  // Frame k of `camera`: renders (with motion blur and rolling shutter), adds noise, quantises.
  // `acc`, `hits`: scratch buffers.
  cv::Mat Render(int camera, int64_t k, std::vector<float>* acc, std::vector<Hit>* hits,
                 RenderKernel kernel) const;

 private:
  // Adds weight x the view of `camera` whose top row is exposed at stream time t_s (the later
  // rows at t_s + RowDelay; the moving objects where they are at each row's time) to `acc`.
  void RenderAt(int camera, double t_s, float weight, std::vector<float>* acc,
                std::vector<Hit>* hits, RenderKernel kernel) const;
  // Applies frame k's light (vignetting, exposure gain) and noise (scaled by the gain) to `acc`
  // (width x height), rounds and saturates to 8 bit.
  cv::Mat Quantise(int camera, int64_t k, const std::vector<float>& acc, int width,
                   int height) const;
};

}  // namespace rigcal::sim::internal
