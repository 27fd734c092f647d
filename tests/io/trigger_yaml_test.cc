// SPDX-License-Identifier: Apache-2.0
// The hardware trigger of a rig config: the top-level `trigger:` section and the cameras'
// `trigger:` entries, their defaults per source (where frames are stamped relative to the
// exposure centre), the sync switching to trigger sequences, and errors naming file:line and
// the field.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "rigcal/io/rig_config.h"
#include "support/temp_dir.h"

namespace rigcal::io {
namespace {

const char* kCamera =
    "    model: pinhole\n"
    "    resolution: [640, 480]\n"
    "    intrinsics: [400, 400, 320, 240]\n"
    "    distortion: [0, 0, 0, 0]\n";

// A two-camera rig with `source` and `trigger` sections and the cameras' extra lines.
std::string Config(const std::string& source, const std::string& trigger, const std::string& cam0,
                   const std::string& cam1, const std::string& extra = "") {
  return "rig: {master: cam0}\n" + source + trigger + extra +
         "cameras:\n"
         "  - name: cam0\n" +
         kCamera + "    device: cam0\n" + cam0 + "  - name: cam1\n" + kCamera +
         "    device: cam1\n"
         "    nominal: {q_wxyz: [1, 0, 0, 0], C: [1, 0, 0]}\n" +
         cam1;
}

Expected<RigConfig> Load(const std::string& text, std::string* path_out = nullptr) {
  static int counter = 0;
  const std::string path =
      (support::FreshTempDir("trigger_yaml_" + std::to_string(counter++)) / "rig.yaml").string();
  std::ofstream(path) << text;
  if (path_out) *path_out = path;
  return LoadRigConfig(path);
}

const std::string kFolders = "source: {type: image_folders}\n";
const std::string kTrigger = "trigger: {port: /dev/ttyACM0}\n";

TEST(TriggerYaml, ReadsTheGeneratorAndTheCamerasLines) {
  auto config = Load(Config(kFolders,
                            "trigger: {port: /dev/ttyUSB1, baud: 230400, rate_hz: 30, "
                            "heartbeat_ms: 50, uart_wire: false, tolerance_ms: 3, "
                            "command_timeout_ms: 200}\n",
                            "    trigger: {line: 0, exposure_us: 4000, exposure_input: "
                            "active_low}\n",
                            "    trigger: {line: 2, phase_us: 100, width_us: 500, exposure_us: "
                            "2000, stamp: end_of_frame, readout_us: 10000}\n"));
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_TRUE(config->trigger.has_value());
  const trigger::LiveTriggerOptions& t = *config->trigger;
  EXPECT_EQ(t.port, "/dev/ttyUSB1");
  EXPECT_EQ(t.baud, 230400);
  EXPECT_FALSE(t.uart_wire);
  EXPECT_DOUBLE_EQ(t.settings.rate_hz, 30);
  EXPECT_EQ(t.settings.heartbeat_ms, 50);
  EXPECT_EQ(t.matcher.tolerance_ns, 3'000'000);
  EXPECT_EQ(t.command_timeout_ms, 200);
  ASSERT_EQ(t.settings.lines.size(), 2u);
  EXPECT_EQ(t.settings.lines[0].line, 0);
  EXPECT_EQ(t.settings.lines[0].width_us, 1000);  // default: min(1000 us, period / 2)
  EXPECT_EQ(t.settings.lines[0].exposure_us, 4000);
  // cam0's exposure output is wired: the generator measures it, the matcher waits for it.
  EXPECT_EQ(t.settings.lines[0].exposure_input, trigger_protocol::ExposureInput::kActiveLow);
  EXPECT_EQ(t.settings.lines[1].exposure_input, trigger_protocol::ExposureInput::kNone);
  EXPECT_EQ(t.settings.lines[1].line, 2);
  EXPECT_EQ(t.settings.lines[1].width_us, 500);
  EXPECT_EQ(t.settings.lines[1].phase_offset_us, 100);
  ASSERT_EQ(config->camera_triggers.size(), 2u);
  // Image folders are stamped at the exposure centre unless `stamp` says otherwise.
  EXPECT_EQ(config->camera_triggers[0]->stamp_offset_ns, 0);
  EXPECT_TRUE(config->camera_triggers[0]->exposure_feedback);
  EXPECT_FALSE(config->camera_triggers[1]->exposure_feedback);
  EXPECT_EQ(config->camera_triggers[1]->line, 2);
  EXPECT_EQ(config->camera_triggers[1]->phase_offset_ns, 100'000);
  EXPECT_EQ(config->camera_triggers[1]->stamp_offset_ns, 1'000'000 + 10'000'000);
  EXPECT_TRUE(config->online.sync.match_by_trigger_seq);  // every camera is triggered
}

TEST(TriggerYaml, DefaultsAndTheSyncFollowTheCameras) {
  // One camera free-running: no matching by sequence; baud and the rest at their defaults.
  auto mixed = Load(Config(kFolders, kTrigger, "    trigger: {line: 1}\n", ""));
  ASSERT_TRUE(mixed.ok()) << mixed.error();
  EXPECT_EQ(mixed->trigger->baud, 115200);
  EXPECT_TRUE(mixed->trigger->uart_wire);
  EXPECT_DOUBLE_EQ(mixed->trigger->settings.rate_hz, 20);
  EXPECT_FALSE(mixed->online.sync.match_by_trigger_seq);
  ASSERT_TRUE(mixed->camera_triggers[0].has_value());
  EXPECT_FALSE(mixed->camera_triggers[1].has_value());
  // An explicit sync setting wins.
  auto explicit_off =
      Load(Config(kFolders, kTrigger, "    trigger: {line: 0}\n", "    trigger: {line: 1}\n",
                  "sync: {match_by_trigger_seq: false}\n"));
  ASSERT_TRUE(explicit_off.ok()) << explicit_off.error();
  EXPECT_FALSE(explicit_off->online.sync.match_by_trigger_seq);
  // No trigger at all: nothing set.
  auto none = Load(Config(kFolders, "", "", ""));
  ASSERT_TRUE(none.ok()) << none.error();
  EXPECT_FALSE(none->trigger.has_value());
}

TEST(TriggerYaml, V4l2CamerasTakeTheExposureOfTheirCaptureAndStampTheStart) {
  // Two cameras on one line (stereo): one generator line; the V4L2 source stamps the start of
  // exposure (buffer flags), so a frame stamp lies half an exposure before the centre.
  auto config = Load(Config("source: {type: v4l2, exposure_us: 5000}\n", kTrigger,
                            "    trigger: {line: 0}\n", "    trigger: {line: 0}\n"));
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_EQ(config->trigger->settings.lines.size(), 1u);
  EXPECT_EQ(config->trigger->settings.lines[0].exposure_us, 5000);
  EXPECT_EQ(config->camera_triggers[0]->stamp_offset_ns, -2'500'000);
  EXPECT_EQ(config->camera_triggers[1]->stamp_offset_ns, -2'500'000);

  auto no_exposure =
      Load(Config("source: {type: v4l2}\n", kTrigger, "    trigger: {line: 0}\n", ""));
  ASSERT_FALSE(no_exposure.ok());
  EXPECT_NE(no_exposure.error().find("cam0.trigger.exposure_us: a triggered v4l2 camera needs "
                                     "capture.exposure_us"),
            std::string::npos)
      << no_exposure.error();
  auto stamp = Load(Config("source: {type: v4l2, exposure_us: 5000}\n", kTrigger,
                           "    trigger: {line: 0, stamp: end_of_frame}\n", ""));
  ASSERT_FALSE(stamp.ok());
  EXPECT_NE(stamp.error().find("cam0.trigger.stamp: a v4l2 camera's stamps follow its buffer"),
            std::string::npos)
      << stamp.error();
}

TEST(TriggerYaml, LibcameraStampsTheStartOfExposure) {
  auto config = Load(Config("source: {type: libcamera}\n", kTrigger,
                            "    trigger: {line: 0, exposure_us: 8000}\n",
                            "    trigger: {line: 1, exposure_us: 8000, stamp: exposure_centre}\n"));
  ASSERT_TRUE(config.ok()) << config.error();
  EXPECT_EQ(config->camera_triggers[0]->stamp_offset_ns, -4'000'000);
  EXPECT_EQ(config->camera_triggers[1]->stamp_offset_ns, 0);
}

TEST(TriggerYaml, TheShippedStereoExampleReads) {
  auto config = LoadRigConfig(std::string(RIGCAL_SOURCE_DIR) + "/config/stereo_v4l2_trigger.yaml");
  ASSERT_TRUE(config.ok()) << config.error();
  EXPECT_EQ(config->trigger->port, "/dev/ttyUSB0");
  ASSERT_EQ(config->trigger->settings.lines.size(), 1u);
  EXPECT_EQ(config->camera_triggers[1]->stamp_offset_ns, -2'000'000);
  EXPECT_TRUE(config->online.sync.match_by_trigger_seq);
}

TEST(TriggerYaml, ASimulatedRigTakesTheGeneratorAtItsFrameRate) {
  const std::string source =
      "source:\n"
      "  type: simulated\n"
      "  frame_rate_hz: 25\n"
      "  trajectory:\n"
      "    waypoints:\n"
      "      - {p: [0, 0, 3], ypr_deg: [0, 0, 0]}\n"
      "      - {p: [1, 0, 3], ypr_deg: [10, 0, 0]}\n";
  const std::string truth = "    truth: {q_wxyz: [1, 0, 0, 0], C: [1, 0, 0]}\n";
  auto good = Load(Config(source, "trigger: {port: /dev/pts/9, rate_hz: 25}\n",
                          "    trigger: {line: 0}\n", truth + "    trigger: {line: 1}\n"));
  ASSERT_TRUE(good.ok()) << good.error();
  EXPECT_EQ(good->camera_triggers[1]->stamp_offset_ns, 0);  // rendered at the exposure centre
  EXPECT_TRUE(good->online.sync.match_by_trigger_seq);
  auto rate = Load(Config(source, "trigger: {port: /dev/pts/9, rate_hz: 20}\n",
                          "    trigger: {line: 0}\n", truth));
  ASSERT_FALSE(rate.ok());
  EXPECT_NE(rate.error().find("trigger.rate_hz: must be the simulated source's frame_rate_hz"),
            std::string::npos)
      << rate.error();
  auto both = Load(Config(source + "  trigger: {}\n", "trigger: {port: /dev/pts/9, rate_hz: 25}\n",
                          "    trigger: {line: 0}\n", truth));
  ASSERT_FALSE(both.ok());
  EXPECT_NE(both.error().find("trigger: not with source.trigger"), std::string::npos)
      << both.error();
}

// Each bad input: the expected "field: what" and the line the error must name.
struct Bad {
  std::string trigger, cam0, cam1, expected;
  int line;
};

TEST(TriggerYaml, ErrorsNameTheFileLineAndField) {
  const Bad cases[] = {
      {"trigger: {port: /dev/ttyACM0, rate: 20}\n", "    trigger: {line: 0}\n", "",
       "trigger.rate: unknown key", 3},
      {"trigger: {baud: 9600}\n", "    trigger: {line: 0}\n", "", "trigger.port: missing", 3},
      {"trigger: {port: /dev/ttyACM0, rate_hz: 1000}\n", "    trigger: {line: 0}\n", "",
       "trigger.rate_hz: must be in [0.1, 400]", 3},
      {"trigger: {port: /dev/ttyACM0, heartbeat_ms: 5}\n", "    trigger: {line: 0}\n", "",
       "trigger.heartbeat_ms: must be 0 (off) or in [10, 10000]", 3},
      {"trigger: {port: /dev/ttyACM0, uart_wire: maybe}\n", "    trigger: {line: 0}\n", "",
       "trigger.uart_wire: expected true or false", 3},
      {"", "    trigger: {line: 0}\n", "", "cam0.trigger: needs the top-level `trigger:`", 10},
      {kTrigger, "", "", "trigger: no camera has a `trigger:` entry", 3},
      {kTrigger, "    trigger: {exposure_us: 10}\n", "", "cam0.trigger.line: missing", 11},
      {kTrigger, "    trigger: {line: 8}\n", "", "cam0.trigger.line: must be in [0, 7]", 11},
      {kTrigger, "    trigger: {line: 0, stamp: middle}\n", "",
       "cam0.trigger.stamp: 'middle' is not one of", 11},
      {kTrigger, "    trigger: {line: 0, width_us: 50000}\n", "",
       "cam0.trigger.width_us: must be below the trigger period 50000 us", 11},
      {kTrigger, "    trigger: {line: 0, phase_us: 40000, exposure_us: 30000}\n", "",
       "cam0.trigger.phase_us: |phase_us| + exposure / 2 must be below", 11},
      {kTrigger, "    trigger: {line: 0, readout_us: 100}\n", "",
       "cam0.trigger.readout_us: only with stamp: end_of_frame", 11},
      {kTrigger, "    trigger: {line: 0, exposure_us: 100}\n",
       "    trigger: {line: 0, exposure_us: 200}\n", "cam1.trigger.line: line 0 is shared", 19},
      {kTrigger, "    trigger: {line: 0, flash: 1}\n", "", "cam0.trigger.flash: unknown key", 11},
      {kTrigger, "    trigger: {line: 0, exposure_input: strobe}\n", "",
       "cam0.trigger.exposure_input: 'strobe' is not one of none, active_high, active_low", 11},
      {kTrigger, "    trigger: {line: 0, width_us: 10}\n", "",
       "cam0.trigger.width_us: must be in [25, 10000000]", 11},
  };
  for (const Bad& bad : cases) {
    std::string path;
    auto config = Load(Config(kFolders, bad.trigger, bad.cam0, bad.cam1), &path);
    ASSERT_FALSE(config.ok()) << bad.expected;
    EXPECT_NE(config.error().find(bad.expected), std::string::npos) << config.error();
    EXPECT_EQ(config.error().rfind(path + ":" + std::to_string(bad.line) + ": ", 0), 0u)
        << config.error() << " (expected line " << bad.line << ")";
  }
}

}  // namespace
}  // namespace rigcal::io
