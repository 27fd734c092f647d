// SPDX-License-Identifier: Apache-2.0
// SimulatedRig::GroundTruth: the simulated rig's true mountings and trajectories as data.
#include "rigcal/sim/simulated_ground_truth.h"
#include "rigcal/sim/simulated_rig.h"
#include "sim_rig_data.h"

namespace rigcal::sim {

SimulatedGroundTruth SimulatedRig::GroundTruth() const {
  SimulatedGroundTruth truth;
  const SimulatedRigSpec& spec = data_->spec;
  for (int c = 0; c < num_cameras(); ++c) {
    SimulatedCameraTruth camera;
    camera.name = spec.names[c];
    camera.master_from_camera.q = spec.master_from_camera[c].q;
    camera.master_from_camera.C = spec.master_from_camera[c].C;
    camera.master_from_camera.scale = 1.0;
    const Pose origin = WorldFromCameraAt(c, 0.0);
    for (int64_t k = 0; k < num_frames(); ++k) {
      const Pose world_from_camera = WorldFromCameraAt(c, FrameStreamTime(k));
      camera.t_ns.push_back(FrameTimeNs(k));
      camera.world_from_camera.push_back(world_from_camera);
      camera.origin_from_camera.push_back(origin.Between(world_from_camera));
    }
    truth.cameras.push_back(std::move(camera));
  }
  return truth;
}

}  // namespace rigcal::sim
