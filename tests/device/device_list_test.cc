// SPDX-License-Identifier: Apache-2.0
// `rigcal devices` and `rigcal check-config` on the guest's vivid devices (scripts/vm): the
// lister finds both vivid capture nodes with their driver, card, bus, formats and sizes; a
// config naming them by bus is checked ok with the negotiated format in its plan, one naming a
// bus that is not there fails with the camera's key.

#include "rigcal/capture/device_list.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "guest_skip.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/config_check.h"

namespace rigcal::capture {
namespace {

TEST(DeviceList, FindsTheVividCaptureNodes) {
  RIGCAL_REQUIRE_NODE("/dev/video0");
  const DeviceList list = ListDevices();
  std::vector<const V4l2NodeInfo*> vivid;
  for (const V4l2NodeInfo& node : list.v4l2) {
    if (node.driver == "vivid") vivid.push_back(&node);
  }
  ASSERT_GE(vivid.size(), 2u) << "v4l2 nodes: " << list.v4l2.size();
  EXPECT_EQ(vivid[0]->bus_info, "platform:vivid-000");
  EXPECT_EQ(vivid[0]->card.rfind("vivid", 0), 0u) << vivid[0]->card;
  const auto grey = std::find_if(vivid[0]->formats.begin(), vivid[0]->formats.end(),
                                 [](const V4l2FormatInfo& f) { return f.fourcc == "GREY"; });
  ASSERT_NE(grey, vivid[0]->formats.end());
  EXPECT_FALSE(grey->sizes.empty());
  const bool has_320x180 =
      std::find(grey->sizes.begin(), grey->sizes.end(), "320x180") != grey->sizes.end();
  EXPECT_TRUE(has_320x180 || grey->sizes.front().find("..") != std::string::npos)
      << grey->sizes.front();
}

io::RigConfig VividRig(const std::string& slave_device) {
  io::RigConfig config;
  config.path = "vivid.yaml";
  for (const char* name : {"cam0", "cam1"}) {
    io::CameraConfig camera;
    camera.name = name;
    config.cameras.push_back(camera);
  }
  for (const std::string& device : {std::string("bus:platform:vivid-000"), slave_device}) {
    V4l2Options options;
    options.device = device;
    options.width = 320;
    options.height = 180;
    options.formats = {PixelFormat::kGrey};
    options.frame_rate_hz = 25;
    config.v4l2_devices.push_back(options);
  }
  return config;
}

TEST(DeviceList, CheckConfigOpensTheCamerasWithoutCapturing) {
  RIGCAL_REQUIRE_NODE("/dev/video0");
  const pipeline::ConfigCheck good =
      pipeline::CheckRigConfig(VividRig("bus:platform:vivid-001"), /*open_devices=*/true);
  EXPECT_TRUE(good.ok()) << good.problems.front();
  std::string plan;
  for (const std::string& line : good.plan) plan += line + "\n";
  EXPECT_NE(plan.find("camera 'cam1': v4l2 bus:platform:vivid-001 320x180"), std::string::npos)
      << plan;
  EXPECT_NE(plan.find("GREY 320x180"), std::string::npos) << plan;
  const pipeline::ConfigCheck bad =
      pipeline::CheckRigConfig(VividRig("bus:platform:nothing-here"), /*open_devices=*/true);
  ASSERT_EQ(bad.problems.size(), 1u);
  EXPECT_NE(bad.problems[0].find("vivid.yaml: cameras[1] 'cam1'.device: "), std::string::npos)
      << bad.problems[0];
}

}  // namespace
}  // namespace rigcal::capture
