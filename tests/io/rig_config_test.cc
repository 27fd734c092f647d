// SPDX-License-Identifier: Apache-2.0
// The rig config loader: camera order, options, and errors that point at the line.
#include "rigcal/io/rig_config.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;

std::string Write(const std::string& text) {
  static int counter = 0;
  const fs::path path =
      fs::temp_directory_path() / ("rigcal_rig_config_" + std::to_string(::getpid()) + "_" +
                                   std::to_string(counter++) + ".yaml");
  std::ofstream(path) << text;
  return path.string();
}

const char kMinimal[] =
    "rig: {master: front}\n"
    "cameras:\n"
    "  - name: left\n"
    "    nominal: {q_wxyz: [0.7071068, 0, 0.7071068, 0], C: [0.5, 0, -0.2]}\n"
    "  - name: front\n";

TEST(RigConfig, MasterFirstNominalAndDefaults) {
  auto config = LoadRigConfig(Write(kMinimal));
  ASSERT_TRUE(config) << config.error();
  ASSERT_EQ(config->CameraNames(), (std::vector<std::string>{"front", "left"}));
  EXPECT_EQ(config->master(), "front");
  EXPECT_FALSE(config->cameras[1].spec.has_value());  // names only: enough for rigcal calib
  ASSERT_EQ(config->online.estimator.nominal.size(), 1u);
  ASSERT_TRUE(config->online.estimator.nominal[0].has_value());
  EXPECT_DOUBLE_EQ(config->online.estimator.nominal[0]->C.x(), 0.5);
  EXPECT_NEAR(config->online.estimator.nominal[0]->q.norm(), 1.0, 1e-15);
  EXPECT_EQ(config->online.sync.num_cameras, 2);
  EXPECT_DOUBLE_EQ(config->publish.extrinsics_rate_hz, PublishOptions().extrinsics_rate_hz);
  EXPECT_TRUE(config->state.path.empty());
  EXPECT_FALSE(config->simulated_source.has_value());
}

// `metric: true` on the master: its pose channel is metric, the estimator keeps positions over
// master re-initialisations (tests/calib/metric_master).
TEST(RigConfig, MetricMaster) {
  auto plain = LoadRigConfig(Write(kMinimal));
  ASSERT_TRUE(plain) << plain.error();
  EXPECT_FALSE(plain->online.estimator.master_metric);
  auto config = LoadRigConfig(Write(std::string(kMinimal) + "    metric: true\n"));
  ASSERT_TRUE(config) << config.error();
  EXPECT_TRUE(config->cameras[0].metric);
  EXPECT_FALSE(config->cameras[0].spec.has_value());  // not an intrinsics key
  EXPECT_TRUE(config->online.estimator.master_metric);
}

TEST(RigConfig, OptionSections) {
  auto config =
      LoadRigConfig(Write(std::string(kMinimal) +
                          "  - name: back\n"
                          "estimator: {half_life_s: 120, window_size: 50,\n"
                          "            keyframe_max_interval_s: 0.5, refine_period_s: 0,\n"
                          "            nominal_sigma: 0.03, min_tilt_snr: 8,\n"
                          "            max_axis_std_ratio: 50, planar_hysteresis: 1.5,\n"
                          "            general_axis_spread_deg: 12,\n"
                          "            alpha_maxrot_noise_deg: 0, sigma_block_s: 5,\n"
                          "            sigma_blocks: 30, keyframe_min_travel_s: 0.25}\n"
                          "sync: {frame_rate_hz: 10, tolerance_ms: 7.5, required: [left]}\n"
                          "publish: {extrinsics_rate_hz: 5, status_rate_hz: 0.5}\n"
                          "state: {path: /tmp/x.state, save_interval_s: 12}\n"));
  ASSERT_TRUE(config) << config.error();
  EXPECT_DOUBLE_EQ(config->online.estimator.half_life_s, 120.0);
  EXPECT_EQ(config->online.estimator.window_size, 50);
  EXPECT_EQ(config->online.estimator.keyframe_max_interval_ns, 500'000'000);
  EXPECT_DOUBLE_EQ(config->online.refine_period_s, 0.0);
  EXPECT_DOUBLE_EQ(config->online.estimator.nominal_sigma, 0.03);
  EXPECT_DOUBLE_EQ(config->online.estimator.model_selection.min_tilt_snr, 8.0);
  EXPECT_DOUBLE_EQ(config->online.estimator.model_selection.max_axis_std_ratio, 50.0);
  EXPECT_DOUBLE_EQ(config->online.estimator.planar_hysteresis, 1.5);
  EXPECT_DOUBLE_EQ(config->online.estimator.model_selection.general_axis_spread_deg, 12.0);
  EXPECT_DOUBLE_EQ(config->online.estimator.model_selection.alpha_maxrot_noise_deg, 0.0);
  EXPECT_DOUBLE_EQ(config->online.estimator.sigma_block_s, 5.0);
  EXPECT_EQ(config->online.estimator.sigma_blocks, 30);
  EXPECT_DOUBLE_EQ(config->online.estimator.keyframe_min_travel_s, 0.25);
  EXPECT_EQ(config->online.sync.frame_period_ns, 100'000'000);
  EXPECT_EQ(config->online.sync.tolerance_ns, 7'500'000);
  EXPECT_EQ(config->online.sync.required, (std::vector<bool>{true, true, false}));
  EXPECT_DOUBLE_EQ(config->publish.extrinsics_rate_hz, 5.0);
  EXPECT_DOUBLE_EQ(config->publish.status_rate_hz, 0.5);
  EXPECT_EQ(config->state.path, "/tmp/x.state");
  EXPECT_DOUBLE_EQ(config->state.save_interval_s, 12.0);
}

struct BadCase {
  std::string text;
  std::string expected;  // substring of the error, including the line number
};

TEST(RigConfig, TimeOffsetAutoSecondsOrPerSlave) {
  const std::string rig =
      "rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n  - name: back\n";
  auto none = LoadRigConfig(Write(rig));
  ASSERT_TRUE(none) << none.error();
  EXPECT_FALSE(none->online.time_offset.enabled) << "synchronised stamps unless configured";
  auto all = LoadRigConfig(Write(rig + "estimator: {time_offset: auto}\n"));
  ASSERT_TRUE(all) << all.error();
  EXPECT_TRUE(all->online.time_offset.enabled);
  EXPECT_EQ(all->online.time_offset.given_s,
            (std::vector<std::optional<double>>{std::nullopt, std::nullopt}));
  auto seconds = LoadRigConfig(Write(rig + "estimator: {time_offset: -0.015}\n"));
  ASSERT_TRUE(seconds) << seconds.error();
  EXPECT_EQ(seconds->online.time_offset.given_s,
            (std::vector<std::optional<double>>{-0.015, -0.015}));
  auto per_slave = LoadRigConfig(Write(rig + "estimator: {time_offset: {back: 0.012}}\n"));
  ASSERT_TRUE(per_slave) << per_slave.error();
  // Camera order: front (master), left, back; left not named: estimated.
  EXPECT_EQ(per_slave->online.time_offset.given_s,
            (std::vector<std::optional<double>>{std::nullopt, 0.012}));
}

TEST(RigConfig, ErrorsNameFileLineAndKey) {
  const std::vector<BadCase> cases = {
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimatr: {}\n",
       ":5: estimatr: unknown key"},
      {"rig: {master: top}\ncameras:\n  - name: front\n  - name: left\n",
       ":1: rig.master: 'top' is not in cameras"},
      // A length in the master's arbitrary unit: removed, the error names its successor.
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n"
       "  keyframe_min_translation: 0.05\n",
       ":6: estimator.keyframe_min_translation: removed: a length in the master's units"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: front\n",
       ":4: cameras[1].name: duplicate camera name 'front'"},
      // A name becomes a file name and part of LCM channel names.
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: ../left\n",
       ":4: cameras[1].name: '/' in a camera name (it becomes a file name)"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: \"le\\tft\"\n",
       ":4: cameras[1].name: a control character in a camera name"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: ..\n",
       ":4: cameras[1].name: '..' cannot name a camera"},
      {"rig: {master: front}\ncameras:\n  - name: front\n    nominal: {q_wxyz: [1,0,0,0], C: "
       "[0,0,0]}\n  - name: left\n",
       "front.nominal: the master defines the rig frame"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n    nominal: {q_wxyz: "
       "[1,0,0], C: [0,0,0]}\n",
       ":5: left.nominal.q_wxyz: expected 4 numbers, got 3"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n    nominal: {q_wxyz: "
       "[2,0,0,0], C: [0,0,0]}\n",
       "left.nominal.q_wxyz: norm 2"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "half_life_s: soon\n",
       ":6: estimator.half_life_s: 'soon' is not a number"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "window_size: 0\n",
       "estimator.window_size"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nsync: {required: "
       "[roof]}\n",
       ":5: sync.required[0]: 'roof' is not a camera of the rig"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\npublish: "
       "{status_rate_hz: -1}\n",
       "publish.status_rate_hz: must be in (0, 1000] Hz"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nsource: {type: "
       "v4l3}\n",
       ":5: source.type: 'v4l3' is not supported"},
      {"rig: {master: front}\ncameras:\n  - name: front\n",
       "cameras: expected a list of at least two"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n    metric: true\n",
       ":5: left.metric: only the master's odometry can be metric"},
      {"rig: {master: front}\ncameras:\n  - name: front\n    metric: yes please\n  - name: "
       "left\n",
       ":4: front.metric: expected true or false"},
      {"rig: [\n", "YAML syntax error"},
      // Strict inputs: duplicate keys (at any depth) and a second document are errors.
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nrig: {master: left}\n",
       ":5: rig: duplicate key"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n    nominal: {q_wxyz: "
       "[1,0,0,0], C: [0,0,0], C: [1,0,0]}\n",
       ":5: C: duplicate key"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n---\nrig: {master: "
       "left}\n",
       ":6: a second YAML document"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\n    truth: {q_wxyz: "
       "[1,0,0,0], C: [0,0,0], skale: 1}\n",
       ":5: left.truth.skale: unknown key"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "time_offset: soon\n",
       ":6: estimator.time_offset: must be auto or a number of seconds, got 'soon'"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "time_offset: {roof: auto}\n",
       ":6: estimator.time_offset.roof: not a camera of the rig"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "time_offset: {front: 0.01}\n",
       ":6: estimator.time_offset.front: the master's clock is the reference"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "time_offset: {left: [1]}\n",
       ":6: estimator.time_offset.left: must be auto or a number of seconds"},
      {"rig: {master: front}\ncameras:\n  - name: front\n  - name: left\nestimator:\n  "
       "time_offset: 1e6\n",
       ":6: estimator.time_offset: must be in [-86400, 86400] s"},
  };
  for (const BadCase& c : cases) {
    const std::string path = Write(c.text);
    auto config = LoadRigConfig(path);
    ASSERT_FALSE(config) << c.text;
    EXPECT_NE(config.error().find(c.expected), std::string::npos)
        << "expected '" << c.expected << "' in: " << config.error();
    EXPECT_EQ(config.error().rfind(path, 0), 0u) << config.error();
  }
  auto missing = LoadRigConfig("/nonexistent/rig.yaml");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().find("/nonexistent/rig.yaml"), std::string::npos);
}

}  // namespace
}  // namespace rigcal::io
