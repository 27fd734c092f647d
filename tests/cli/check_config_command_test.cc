// SPDX-License-Identifier: Apache-2.0
// `rigcal check-config` and `rigcal devices` on this machine, through the built binary: the
// installed example rigs are valid, a config naming devices that are not here fails with every
// camera and the trigger's port named, a typo names the file, line and key; `devices --json`
// is JSON with every section. (With cameras: tests/device, in the guest.)
#include <nlohmann/json.hpp>

#include "command_test.h"

namespace {

using rigcal::cli_test::CommandTest;
using rigcal::cli_test::RunResult;

std::string Example(const std::string& name) {
  return std::string(RIGCAL_SOURCE_DIR) + "/config/" + name;
}

TEST_F(CommandTest, ExampleRigsAreValid) {
  for (const char* name : {"examples/surround4_v4l2.yaml", "examples/libcamera_stereo.yaml",
                           "stereo_v4l2_trigger.yaml", "sim_thesis_virtual.yaml"}) {
    const RunResult r = Run("check-config --no-open " + Example(name));
    EXPECT_EQ(r.exit_code, 0) << name << "\n" << r.Explain();
    EXPECT_NE(r.out.find("rigcal run would run:"), std::string::npos) << r.out;
  }
  const RunResult sim = Run("check-config " + Example("sim_thesis_virtual.yaml"));
  EXPECT_EQ(sim.exit_code, 0) << sim.Explain();
  EXPECT_NE(sim.out.find("source: the simulated rig"), std::string::npos) << sim.out;
}

TEST_F(CommandTest, MissingDevicesAreEachNamed) {
  std::string yaml = rigcal::cli_test::Slurp(Example("stereo_v4l2_trigger.yaml"));
  const std::string absent = "/dev/rigcal-test-no-such-";
  for (const char* from : {"/dev/v4l/by-id/usb-left-video-index0",
                           "/dev/v4l/by-id/usb-right-video-index0", "/dev/ttyUSB0"}) {
    const size_t at = yaml.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    yaml.replace(at, std::string(from).size(), absent + std::to_string(at));
  }
  std::ofstream(Path("rig.yaml")) << yaml;
  const RunResult r = Run("check-config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  // Each names the file and the line of its key (config/stereo_v4l2_trigger.yaml), like the
  // loader's errors, and the device.
  const std::string at = "FAIL " + Path("rig.yaml") + ":";
  EXPECT_NE(r.out.find(at + "23: cameras[0] 'left'.device: camera left: " + absent),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find(at + "30: cameras[1] 'right'.device: camera right: " + absent),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find(at + "12: trigger.port: " + absent), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("3 problem(s)"), std::string::npos) << r.out;
}

// A v4l2 rig written by hand with a device path that does not exist: the FAIL line names the
// file, the line of the camera's `device:` and the key, then the device and why.
TEST_F(CommandTest, AnAbsentDeviceNamesFileLineAndKey) {
  std::ofstream(Path("rig.yaml")) << "rig: {name: x, master: a}\n"                     // 1
                                     "source: {type: v4l2}\n"                          // 2
                                     "cameras:\n"                                      // 3
                                     "  - name: a\n"                                   // 4
                                     "    model: pinhole\n"                            // 5
                                     "    resolution: [640, 480]\n"                    // 6
                                     "    intrinsics: [500, 500, 320, 240]\n"          // 7
                                     "    device: /dev/rigcal-test-no-such-video8\n"   // 8
                                     "  - name: b\n"                                   // 9
                                     "    model: pinhole\n"                            // 10
                                     "    resolution: [640, 480]\n"                    // 11
                                     "    intrinsics: [500, 500, 320, 240]\n"          // 12
                                     "    device: /dev/rigcal-test-no-such-video9\n";  // 13
  const RunResult r = Run("check-config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  EXPECT_NE(r.out.find("FAIL " + Path("rig.yaml") +
                       ":13: cameras[1] 'b'.device: camera b: /dev/rigcal-test-no-such-video9: "),
            std::string::npos)
      << r.out;
}

TEST_F(CommandTest, TypoNamesFileLineAndKey) {
  std::ofstream(Path("rig.yaml")) << "rig: {name: x, master: a}\ncameras:\n  - name: a\n"
                                     "  - name: b\npublish:\n  extrinsic_rate_hz: 2\n";
  const RunResult r = Run("check-config " + Path("rig.yaml"));
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  EXPECT_NE(r.out.find(Path("rig.yaml") + ":6"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("extrinsic_rate_hz"), std::string::npos) << r.out;
}

TEST_F(CommandTest, DevicesJsonHasEverySection) {
  const RunResult r = Run("devices --json");
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  const nlohmann::json json = nlohmann::json::parse(r.out);
  EXPECT_TRUE(json["v4l2"].is_array());
  EXPECT_TRUE(json["serial"].is_array());
  EXPECT_TRUE(json["libcamera"]["cameras"].is_array());
  const RunResult text = Run("devices");
  EXPECT_EQ(text.exit_code, 0) << text.Explain();
  EXPECT_NE(text.out.find("serial ports for a trigger generator"), std::string::npos) << text.out;
}

}  // namespace
