// SPDX-License-Identifier: Apache-2.0
#pragma once
// SimulatedGroundTruth: what a simulated drive truly was, as plain data (SimulatedRig::
// GroundTruth); rigcal_io writes it as files (rigcal/io/ground_truth_files.h,
// `rigcal run --truth-out DIR`).

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::sim {

// One camera's truth. Poses are sampled at every nominal frame stamp; metres, the camera frame
// as everywhere (x right, y down, z forward).
struct SimulatedCameraTruth {
  std::string name;
  // The camera's mounting in the master frame with scale 1 (the simulated truth is metric); the
  // identity for the master.
  Similarity master_from_camera;
  std::vector<int64_t> t_ns;  // SimulatedRig::FrameTimeNs(k), k = 0 .. num_frames - 1
  // The camera's pose in the simulated world (z up) at t_ns[k].
  std::vector<Pose> world_from_camera;
  // The same in the camera's own reference frame, its pose at frame 0 (thesis
  // T_i^k = (T_i,world^0)^-1 T_i,world^k): origin_from_camera[0] is the identity.
  std::vector<Pose> origin_from_camera;
};

struct SimulatedGroundTruth {
  std::vector<SimulatedCameraTruth> cameras;  // in rig order: the master first
};

}  // namespace rigcal::sim
