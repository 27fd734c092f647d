// SPDX-License-Identifier: Apache-2.0
// A camera moving through the simulated rig's room (room_sequence.h).
#include "support/room_sequence.h"

#include <cmath>
#include <utility>

#include "rigcal/base/quaternion.h"

namespace rigcal::support {

Pose RoomCentre() {
  Pose centre;
  centre.q = sim::WaypointOrientationFromYpr(0.0, 0.0, 0.0);
  centre.C = Eigen::Vector3d(0.0, 0.0, 3.0);
  return centre;
}

Pose RoomPose(int k) {
  const double t = k / kRoomFrameRateHz;
  Pose motion;  // relative to RoomCentre()
  motion.C = Eigen::Vector3d(1.2 * std::sin(0.5 * t), 0.4 * std::sin(0.7 * t + 0.3),
                             0.9 * std::sin(0.33 * t + 1.0) - 0.5);
  const double yaw = 0.35 * std::sin(0.4 * t);
  const double pitch = 0.15 * std::sin(0.6 * t + 0.5);
  const double roll = 0.1 * std::sin(0.5 * t + 1.3);
  motion.q = AxisAngle(Eigen::Vector3d::UnitY(), yaw) * AxisAngle(Eigen::Vector3d::UnitX(), pitch) *
             AxisAngle(Eigen::Vector3d::UnitZ(), roll);
  return RoomCentre() * motion;
}

Expected<sim::SimulatedRig> MakeRoomSequence(std::shared_ptr<const camera::CameraModel> camera,
                                             const std::vector<Pose>& world_from_camera,
                                             double noise_sigma) {
  sim::SimulatedRigSpec spec;
  spec.names = {"cam0"};
  spec.cameras = {std::move(camera)};
  spec.master_from_camera = {Pose()};
  spec.frame_rate_hz = kRoomFrameRateHz;
  spec.seed = 7;
  for (size_t k = 0; k < world_from_camera.size(); ++k) {
    spec.trajectory_t_ns.push_back(std::llround(static_cast<double>(k) * 1e9 / kRoomFrameRateHz));
  }
  spec.trajectory_world_from_body = world_from_camera;
  spec.scene.type = sim::SimulatedRigSpec::SceneType::kRoom;
  spec.scene.size = Eigen::Vector3d(10.0, 8.0, 6.0);
  spec.scene.boxes = 0;
  spec.noise_sigma = noise_sigma;
  return sim::MakeSimulatedRig(std::move(spec));
}

}  // namespace rigcal::support
