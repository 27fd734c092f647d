// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated rig of the pipeline tests: three 480x320 pinhole cameras (front, side, up) in the
// default room, moving and rotating about varied axes (no threads: room_rig.h adds running a
// pipeline on it).
#include <gtest/gtest.h>

#include <string>

#include "rigcal/base/quaternion.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::pipeline {

// The intrinsics of every camera of the rig.
inline camera::CameraSpec RoomRigCameraSpec(const std::string& name) {
  camera::CameraSpec spec;
  spec.name = name;
  spec.model = camera::CameraSpec::Model::kPinhole;
  spec.width = 480;
  spec.height = 320;
  spec.intrinsics = {300.0, 300.0, 240.0, 160.0};
  return spec;
}

// The rig for `seconds` at 20 Hz.
inline sim::SimulatedRigSpec RoomRigSpec(double seconds) {
  sim::SimulatedRigSpec spec;
  spec.names = {"front", "side", "up"};
  for (const std::string& name : spec.names) {
    auto model = camera::MakeCameraModel(RoomRigCameraSpec(name));
    EXPECT_TRUE(model) << model.error();
    spec.cameras.emplace_back(std::move(*model));
  }
  Pose side;
  side.q = AxisAngle(Eigen::Vector3d::UnitY(), 70.0 * kRadPerDeg);
  side.C = Eigen::Vector3d(0.4, 0.0, -0.2);
  Pose up;
  up.q = AxisAngle(Eigen::Vector3d::UnitX(), 60.0 * kRadPerDeg);
  up.C = Eigen::Vector3d(0.0, -0.3, 0.1);
  spec.master_from_camera = {Pose(), side, up};
  spec.frame_rate_hz = 20.0;
  spec.duration_s = seconds;
  spec.noise_sigma = 1.0;
  spec.waypoint_interval_s = 2.0;
  // Around the middle of the room at 2-3 m height, yawing, pitching and rolling.
  const double ypr[][3] = {{0, 0, 0},     {25, 8, 5},   {50, -6, -8}, {20, 12, 10},
                           {-15, -10, 0}, {-40, 5, -6}, {-10, -8, 8}, {15, 10, -5},
                           {40, 0, 6},    {10, -10, 0}, {-20, 6, 8},  {0, 0, 0}};
  const double p[][3] = {{-2, 0, 2.5},     {-1, 1, 2.8},     {0, 1.5, 2.2},     {1, 0.5, 2.6},
                         {1.5, -1, 2.9},   {0.5, -1.5, 2.3}, {-0.5, -0.5, 2.7}, {-1.5, 0.5, 2.4},
                         {-0.5, 1.2, 2.6}, {0.8, 0.8, 2.2},  {1.2, -0.6, 2.8},  {0, 0, 2.5}};
  for (int i = 0; i < 12; ++i) {
    sim::SimulatedRigSpec::Waypoint w;
    w.position = Eigen::Vector3d(p[i][0], p[i][1], p[i][2]);
    w.world_from_master = sim::WaypointOrientationFromYpr(ypr[i][0], ypr[i][1], ypr[i][2]);
    spec.waypoints.push_back(w);
  }
  return spec;
}

}  // namespace rigcal::pipeline
