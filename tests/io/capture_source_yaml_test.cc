// SPDX-License-Identifier: Apache-2.0
// The capture sources of a rig config (source.type v4l2 / libcamera / image_folders): defaults
// at the source, overrides per camera, the camera's size, and errors that name the line and
// field.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "rigcal/io/rig_config.h"
#include "support/temp_dir.h"

namespace rigcal::io {
namespace {

std::string Write(const std::string& name, const std::string& text) {
  const std::string path = (support::FreshTempDir("capture_yaml_" + name) / "rig.yaml").string();
  std::ofstream(path) << text;
  return path;
}

const char kCameras[] =
    "rig: {master: front}\n"
    "cameras:\n"
    "  - name: front\n"
    "    model: pinhole\n"
    "    resolution: [640, 480]\n"
    "    intrinsics: [500, 500, 319.5, 239.5]\n"
    "    device: /dev/v4l/by-id/usb-cam-front\n"
    "  - name: left\n"
    "    model: pinhole\n"
    "    resolution: [320, 240]\n"
    "    intrinsics: [250, 250, 159.5, 119.5]\n"
    "    device: bus:usb-0000:00:14.0-2\n";

TEST(CaptureSourceYaml, V4l2DefaultsAndOverrides) {
  const std::string path = Write("v4l2", std::string(kCameras) +
                                             "    capture: {pixel_formats: [mjpeg], gain: 12,\n"
                                             "              external_trigger: true,\n"
                                             "              controls: {power_line_frequency: 1}}\n"
                                             "source:\n"
                                             "  type: v4l2\n"
                                             "  pixel_formats: [GREY, YUYV]\n"
                                             "  frame_rate_hz: 30\n"
                                             "  buffers: 6\n"
                                             "  exposure_us: 4000\n"
                                             "  readout_us: 15000\n"
                                             "  reconnect_max_backoff_s: 1.5\n");
  auto config = LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->v4l2_devices.size(), 2u);
  const capture::V4l2Options& front = config->v4l2_devices[0];
  EXPECT_EQ(front.device, "/dev/v4l/by-id/usb-cam-front");
  EXPECT_EQ(front.width, 640);
  EXPECT_EQ(front.height, 480);
  EXPECT_EQ(front.formats, (std::vector<capture::PixelFormat>{capture::PixelFormat::kGrey,
                                                              capture::PixelFormat::kYuyv}));
  EXPECT_DOUBLE_EQ(front.frame_rate_hz, 30.0);
  EXPECT_EQ(front.buffers, 6);
  ASSERT_TRUE(front.exposure_us.has_value());
  EXPECT_DOUBLE_EQ(*front.exposure_us, 4000.0);
  EXPECT_DOUBLE_EQ(front.readout_us, 15000.0);
  EXPECT_FALSE(front.gain.has_value());
  EXPECT_FALSE(front.external_trigger);
  EXPECT_TRUE(front.Check().ok()) << front.Check().message();
  const capture::V4l2Options& left = config->v4l2_devices[1];
  EXPECT_EQ(left.device, "bus:usb-0000:00:14.0-2");
  EXPECT_EQ(left.width, 320);
  EXPECT_EQ(left.formats, (std::vector<capture::PixelFormat>{capture::PixelFormat::kMjpeg}));
  EXPECT_EQ(left.gain, 12);
  EXPECT_TRUE(left.external_trigger);
  EXPECT_EQ(left.controls.at("power_line_frequency"), 1);
  EXPECT_EQ(left.buffers, 6);  // the source's default
  EXPECT_DOUBLE_EQ(left.reconnect_max_backoff_s, 1.5);
}

TEST(CaptureSourceYaml, ErrorsNameTheLineAndField) {
  struct Case {
    std::string text;
    std::string expected;
  };
  const std::string v4l2 = "source: {type: v4l2}\n";
  const std::vector<Case> cases = {
      {std::string(kCameras) + "    capture: {gian: 3}\n" + v4l2,
       "rig.yaml:13: left.capture.gian: unknown key"},
      {std::string(kCameras) + "    capture: {pixel_formats: [RGB3]}\n" + v4l2,
       "rig.yaml:13: left.capture.pixel_formats[0]: 'RGB3' is not one of"},
      {std::string(kCameras) + "source: {type: v4l2, buffers: 1}\n",
       "rig.yaml:13: source.buffers: must be in [2, 32]"},
      {std::string(kCameras) + "source: {type: v4l2, frame_rate_hz: -5}\n",
       "source.frame_rate_hz: must be in"},
      {std::string(kCameras) + "    capture: {gain: 3}\nsource: {type: simulated}\n",
       "cameras[1].capture: only for a live source"},
      {"rig: {master: a}\ncameras:\n"
       "  - {name: a, model: pinhole, resolution: [8, 8], intrinsics: [8, 8, 3.5, 3.5]}\n"
       "  - {name: b, model: pinhole, resolution: [8, 8], intrinsics: [8, 8, 3.5, 3.5]}\n" +
           v4l2,
       "a.device: missing: a v4l2 camera needs its device"},
      {std::string(kCameras) + "source: {type: firewire}\n",
       "'firewire' is not supported (supported: simulated, image_folders, v4l2, libcamera)"},
      {std::string(kCameras) + "source: {type: libcamera, role: movie}\n",
       "source.role: 'movie' is not one of video, viewfinder, still, raw"},
  };
  int i = 0;
  for (const Case& c : cases) {
    auto config = LoadRigConfig(Write("error" + std::to_string(i++), c.text));
    ASSERT_FALSE(config.ok()) << c.text;
    EXPECT_NE(config.error().find(c.expected), std::string::npos)
        << "got: " << config.error() << "\nexpected: " << c.expected;
  }
}

TEST(CaptureSourceYaml, LibcameraCameraByModel) {
  auto config = LoadRigConfig(Write("libcamera", std::string(kCameras) +
                                                     "    capture: {role: viewfinder}\n"
                                                     "source: {type: libcamera, buffers: 3,\n"
                                                     "         pixel_formats: [NV12, BGR24]}\n"));
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->libcamera_devices.size(), 2u);
  EXPECT_EQ(config->libcamera_devices[0].camera, "/dev/v4l/by-id/usb-cam-front");
  EXPECT_EQ(config->libcamera_devices[0].role, "video");
  EXPECT_EQ(config->libcamera_devices[1].role, "viewfinder");
  EXPECT_EQ(config->libcamera_devices[1].buffers, 3);
  EXPECT_EQ(config->libcamera_devices[1].width, 320);
  EXPECT_EQ(config->libcamera_devices[1].formats.size(), 2u);
}

// Plain image folders: the source's rate and timestamps file (resolved against the config's
// folder) are every camera's defaults; a camera's `capture:` overrides them.
TEST(CaptureSourceYaml, ImageFolderRateAndTimestamps) {
  const std::string path = Write("folders", std::string(kCameras) +
                                                "    capture: {timestamps: left_stamps.txt}\n"
                                                "source: {type: image_folders, rate_hz: 30}\n");
  auto config = LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->image_folders.size(), 2u);
  ASSERT_EQ(config->image_folder_options.size(), 2u);
  EXPECT_DOUBLE_EQ(config->image_folder_options[0].rate_hz, 30.0);
  EXPECT_TRUE(config->image_folder_options[0].timestamps_file.empty());
  EXPECT_DOUBLE_EQ(config->image_folder_options[1].rate_hz, 30.0);
  EXPECT_EQ(config->image_folder_options[1].timestamps_file,
            (std::filesystem::path(path).parent_path() / "left_stamps.txt").string());

  const std::string bad =
      Write("folders_bad", std::string(kCameras) + "source: {type: image_folders, rate_hz: 0}\n");
  auto rejected = LoadRigConfig(bad);
  ASSERT_FALSE(rejected.ok());
  EXPECT_NE(rejected.error().find("source.rate_hz: must be in (0, 10000]"), std::string::npos)
      << rejected.error();
  const std::string typo = Write("folders_typo", std::string(kCameras) +
                                                     "    capture: {rate: 30}\n"
                                                     "source: {type: image_folders}\n");
  auto unknown = LoadRigConfig(typo);
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().find("left.capture.rate"), std::string::npos) << unknown.error();
}

}  // namespace
}  // namespace rigcal::io
