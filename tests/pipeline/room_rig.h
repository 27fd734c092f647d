#pragma once
// The simulated rig of the pipeline tests: three 480x320 pinhole cameras (front, side, up) in the
// default room, moving and rotating about varied axes; a run of a pipeline to its end; a rig's
// images as an LCM log.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>

#include "rigcal/calib/quaternion.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/drivers/simulated_rig.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/pipeline/image_codec.h"
#include "rigcal/pipeline/pipeline.h"

namespace rigcal::tools {

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
inline drivers::SimulatedRigSpec RoomRigSpec(double seconds) {
  drivers::SimulatedRigSpec spec;
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
    drivers::SimulatedRigSpec::Waypoint w;
    w.position = Eigen::Vector3d(p[i][0], p[i][1], p[i][2]);
    w.world_from_master = drivers::WaypointOrientationFromYpr(ypr[i][0], ypr[i][1], ypr[i][2]);
    spec.waypoints.push_back(w);
  }
  return spec;
}

// Starts `pipeline`, waits (at most 5 minutes) until every camera's stream has been processed,
// stops it; false when it did not finish in time.
inline bool RunToEnd(Pipeline* pipeline) {
  pipeline->Start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (!pipeline->Finished() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const bool finished = pipeline->Finished();
  pipeline->Stop();
  return finished;
}

// Every frame of the rig as an image log, in stamp order (master first at equal stamps).
inline void WriteImageLog(const drivers::SimulatedRig& rig, const std::vector<std::string>& names,
                          const std::string& path) {
  std::vector<drivers::Frame> frames;
  auto devices = rig.MakeDevices();
  for (size_t i = 0; i < devices.size(); ++i) {
    while (true) {
      auto grabbed = devices[i]->Grab();
      ASSERT_TRUE(grabbed) << grabbed.error();
      if (!grabbed->has_value()) break;
      frames.push_back(std::move(**grabbed));
      frames.back().camera = static_cast<int>(i);
    }
  }
  std::stable_sort(frames.begin(), frames.end(), [](const auto& a, const auto& b) {
    return a.t_ns != b.t_ns ? a.t_ns < b.t_ns : a.camera < b.camera;
  });
  lcm::LogFile log(path, "w");
  ASSERT_TRUE(log.good());
  int64_t n = 0;
  for (const drivers::Frame& frame : frames) {
    const std::string& name = names[static_cast<size_t>(frame.camera)];
    const std::string channel = ImageChannel(name);
    auto bytes = EncodeImageEvent(frame, names, frame.camera, {});
    ASSERT_TRUE(bytes) << bytes.error();
    lcm::LogEvent event;
    event.eventnum = n++;
    event.timestamp = frame.t_ns / 1000;
    event.channel = channel;
    event.datalen = static_cast<int32_t>(bytes->size());
    event.data = bytes->data();
    ASSERT_EQ(log.writeEvent(&event), 0);
  }
}

}  // namespace rigcal::tools
