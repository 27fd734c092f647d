// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pipeline tests' rig (room_rig_spec.h): a run of a pipeline to its end; a rig's images as an
// LCM log.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>

#include "pipeline/room_rig_spec.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/pipeline/image_codec.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::pipeline {

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
inline void WriteImageLog(const sim::SimulatedRig& rig, const std::vector<std::string>& names,
                          const std::string& path) {
  std::vector<capture::Frame> frames;
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
  ::lcm::LogFile log(path, "w");
  ASSERT_TRUE(log.good());
  int64_t n = 0;
  for (const capture::Frame& frame : frames) {
    const std::string& name = names[static_cast<size_t>(frame.camera)];
    const std::string channel = lcm::ImageChannel(name);
    auto bytes = EncodeImageEvent(frame, names, frame.camera, {});
    ASSERT_TRUE(bytes) << bytes.error();
    ::lcm::LogEvent event;
    event.eventnum = n++;
    event.timestamp = frame.t_ns / 1000;
    event.channel = channel;
    event.datalen = static_cast<int32_t>(bytes->size());
    event.data = bytes->data();
    ASSERT_EQ(log.writeEvent(&event), 0);
  }
}

}  // namespace rigcal::pipeline
