// SPDX-License-Identifier: Apache-2.0
// The `source:` section of a simulated rig config, and the shipped simulation configs: every key
// parsed, errors that name the line and key, and configs whose motion a VO can track.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "../../tools/io/src/config_sections.h"
#include "../../tools/io/src/yaml_fields.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/io/rig_config.h"

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;
using sim::SimulatedRigSpec;

fs::path TempDir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("rigcal_sim_source_" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

std::string Write(const std::string& name, const std::string& text) {
  const fs::path path = TempDir() / name;
  std::ofstream(path) << text;
  return path.string();
}

// Parses `text` (a YAML document whose `source:` key holds the section) from a file.
Expected<SimulatedRigSpec> Parse(const std::string& text, std::string* path_out = nullptr) {
  static int counter = 0;
  const std::string path = Write("source_" + std::to_string(counter++) + ".yaml", text);
  if (path_out) *path_out = path;
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  return ParseSimulatedSource((*root)["source"], path);
}

const char kWaypoints[] =
    "  trajectory:\n"
    "    waypoint_interval_s: 2\n"
    "    waypoints:\n"
    "      - {p: [0, 0, 3], ypr_deg: [0, 0, 0]}\n"
    "      - {p: [1, 0.5, 3], ypr_deg: [30, 5, -5]}\n"
    "      - {p: [2, 0, 3], q_wxyz: [1, 0, 0, 0]}\n";

TEST(SimulatedSourceYaml, ParsesEveryKey) {
  auto spec = Parse(
      std::string("source:\n"
                  "  type: simulated\n"
                  "  frame_rate_hz: 25\n"
                  "  duration_s: 3.5\n"
                  "  seed: 42\n"
                  "  realtime: true\n"
                  "  noise_sigma: 2.5\n"
                  "  motion_blur: {exposure_ms: 8, samples: 5}\n"
                  "  drop_probability: 0.1\n"
                  "  timestamp_jitter_ms: 1.5\n"
                  "  fail_after_s: {cam1: 2.5}\n"
                  "  render_block: 2\n"
                  "  vignetting: 0.3\n"
                  "  rolling_shutter_ms: 12.5\n"
                  "  exposure_steps: {interval_s: 2, max_factor: 1.5}\n"
                  "  scene: {type: yard, size: [40, 30, 7], boxes: 3, texel_m: 0.015,\n"
                  "          moving_objects: {count: 5, size: [4, 1.8, 1.5], speed_mps: 8}}\n") +
      kWaypoints);
  ASSERT_TRUE(spec) << spec.error();
  EXPECT_DOUBLE_EQ(spec->frame_rate_hz, 25.0);
  EXPECT_DOUBLE_EQ(spec->duration_s, 3.5);
  EXPECT_EQ(spec->num_frames, 0);
  EXPECT_EQ(spec->seed, 42u);
  EXPECT_TRUE(spec->realtime);
  EXPECT_DOUBLE_EQ(spec->noise_sigma, 2.5);
  EXPECT_DOUBLE_EQ(spec->blur_exposure_s, 0.008);
  EXPECT_EQ(spec->blur_samples, 5);
  EXPECT_DOUBLE_EQ(spec->drop_probability, 0.1);
  EXPECT_DOUBLE_EQ(spec->timestamp_jitter_s, 0.0015);
  ASSERT_EQ(spec->fail_after_s.count("cam1"), 1u);
  EXPECT_DOUBLE_EQ(spec->fail_after_s.at("cam1"), 2.5);
  EXPECT_EQ(spec->render_block, 2);
  EXPECT_DOUBLE_EQ(spec->vignetting, 0.3);
  EXPECT_DOUBLE_EQ(spec->rolling_shutter_s, 0.0125);
  EXPECT_DOUBLE_EQ(spec->exposure_steps.interval_s, 2.0);
  EXPECT_DOUBLE_EQ(spec->exposure_steps.max_factor, 1.5);
  EXPECT_EQ(spec->scene.type, SimulatedRigSpec::SceneType::kYard);
  EXPECT_EQ(spec->scene.size, Eigen::Vector3d(40, 30, 7));
  EXPECT_EQ(spec->scene.boxes, 3);
  EXPECT_DOUBLE_EQ(spec->scene.texel_m, 0.015);
  EXPECT_EQ(spec->scene.moving_objects.count, 5);
  EXPECT_EQ(spec->scene.moving_objects.size_m, Eigen::Vector3d(4, 1.8, 1.5));
  EXPECT_DOUBLE_EQ(spec->scene.moving_objects.speed_mps, 8.0);
  EXPECT_DOUBLE_EQ(spec->waypoint_interval_s, 2.0);
  ASSERT_EQ(spec->waypoints.size(), 3u);
  EXPECT_EQ(spec->waypoints[1].position, Eigen::Vector3d(1, 0.5, 3));
  EXPECT_LT(spec->waypoints[1].world_from_master.angularDistance(
                sim::WaypointOrientationFromYpr(30, 5, -5)),
            1e-12);
  EXPECT_LT(spec->waypoints[2].world_from_master.angularDistance(Eigen::Quaterniond::Identity()),
            1e-12);
  EXPECT_TRUE(spec->names.empty());  // cameras are the caller's
}

TEST(SimulatedSourceYaml, DefaultsAndPipe) {
  auto spec = Parse(std::string("source:\n"
                                "  num_frames: 20\n"
                                "  motion_blur: false\n"
                                "  scene: {type: pipe, diameter: 0.8, length: 25}\n") +
                    kWaypoints);
  ASSERT_TRUE(spec) << spec.error();
  const SimulatedRigSpec defaults;
  EXPECT_EQ(spec->num_frames, 20);
  EXPECT_DOUBLE_EQ(spec->frame_rate_hz, defaults.frame_rate_hz);
  EXPECT_FALSE(spec->realtime);
  EXPECT_DOUBLE_EQ(spec->blur_exposure_s, 0.0);
  EXPECT_DOUBLE_EQ(spec->noise_sigma, defaults.noise_sigma);
  EXPECT_EQ(spec->scene.type, SimulatedRigSpec::SceneType::kPipe);
  EXPECT_DOUBLE_EQ(spec->scene.pipe_diameter, 0.8);
  EXPECT_DOUBLE_EQ(spec->scene.pipe_length, 25.0);
  EXPECT_DOUBLE_EQ(spec->TexelSize(), 0.002);
  EXPECT_EQ(spec->scene.moving_objects.count, 0);  // none unless asked for
}

TEST(SimulatedSourceYaml, TrajectoryFileRelativeToTheConfig) {
  // TUM: t tx ty tz qx qy qz qw (a body moving along x, yawing).
  Write("drive.tum",
        "# t tx ty tz qx qy qz qw\n"
        "100.0 0 0 1.5 0 0 0 1\n"
        "101.0 1 0 1.5 0 0 0.0871557 0.9961947\n"
        "102.0 2 0 1.5 0 0 0 1\n");
  auto spec = Parse(
      "source:\n"
      "  trajectory:\n"
      "    file: drive.tum\n"
      "    body_from_master: {q_wxyz: [0.5, -0.5, 0.5, -0.5], C: [0.1, 0, 0]}\n");
  ASSERT_TRUE(spec) << spec.error();
  ASSERT_EQ(spec->trajectory_world_from_body.size(), 3u);
  EXPECT_EQ(spec->trajectory_t_ns[1] - spec->trajectory_t_ns[0], 1'000'000'000);
  EXPECT_DOUBLE_EQ(spec->trajectory_world_from_body[2].C.x(), 2.0);
  EXPECT_NE(spec->trajectory_file.find("drive.tum"), std::string::npos);
  EXPECT_DOUBLE_EQ(spec->body_from_master.C.x(), 0.1);
  EXPECT_TRUE(spec->waypoints.empty());
  // The body_from_master above makes a camera looking along the body's x axis, level: the same
  // as a waypoint with ypr (0, 0, 0).
  EXPECT_LT(spec->body_from_master.q.angularDistance(sim::WaypointOrientationFromYpr(0, 0, 0)),
            1e-9);
}

struct BadCase {
  std::string text;
  std::string expected;  // substring of the error, with the line number
};

TEST(SimulatedSourceYaml, TexturePhotographsRelativeToTheConfig) {
  cv::Mat colour(30, 50, CV_8UC3, cv::Scalar(30, 60, 90));
  ASSERT_TRUE(cv::imwrite((TempDir() / "wall.png").string(), colour));
  cv::Mat deep(20, 20, CV_16U, cv::Scalar(40000));
  ASSERT_TRUE(cv::imwrite((TempDir() / "box.png").string(), deep));
  auto spec =
      Parse("source:\n  scene:\n    textures: [wall.png, box.png]\n" + std::string(kWaypoints));
  ASSERT_TRUE(spec) << spec.error();
  ASSERT_EQ(spec->scene.textures.size(), 2u);
  const SimulatedRigSpec::GreyImage& wall = spec->scene.textures[0];
  EXPECT_EQ(wall.width, 50);
  EXPECT_EQ(wall.height, 30);
  ASSERT_EQ(wall.pixels.size(), 1500u);
  EXPECT_NEAR(wall.pixels[0], 0.114 * 30 + 0.587 * 60 + 0.299 * 90, 1.0);  // BGR to grey
  EXPECT_NE(wall.name.find("wall.png"), std::string::npos);
  EXPECT_NEAR(spec->scene.textures[1].pixels[0], 40000.0 / 257.0, 1.0);  // 16 bit to 8 bit

  ASSERT_TRUE(cv::imwrite((TempDir() / "tiny.png").string(), cv::Mat(8, 8, CV_8U, 7)));
  Write("not_an_image.png", "text\n");
  const std::string w = kWaypoints;
  const std::vector<BadCase> cases = {
      {"source:\n  scene:\n    textures: [missing.png]\n" + w, ":3: source.scene.textures[0]: "},
      {"source:\n  scene:\n    textures:\n      - wall.png\n      - not_an_image.png\n" + w,
       ":5: source.scene.textures[1]: "},
      {"source:\n  scene:\n    textures: [tiny.png]\n" + w, ":3: source.scene.textures[0]: "},
      {"source:\n  scene:\n    textures: []\n" + w,
       ":3: source.scene.textures: must be a non-empty list"},
      {"source:\n  scene:\n    textures: wall.png\n" + w,
       ":3: source.scene.textures: must be a non-empty list"},
  };
  for (const BadCase& c : cases) {
    auto bad = Parse(c.text);
    ASSERT_FALSE(bad) << c.text;
    EXPECT_NE(bad.error().find(c.expected), std::string::npos) << bad.error();
  }
  EXPECT_NE(Parse(cases[0].text).error().find("missing.png: no such file"), std::string::npos);
  EXPECT_NE(Parse(cases[1].text).error().find("not_an_image.png: not a readable image"),
            std::string::npos);
  EXPECT_NE(Parse(cases[2].text).error().find("needs at least 16 px"), std::string::npos);
}

TEST(SimulatedSourceYaml, ErrorsNameLineAndKey) {
  const std::string w = kWaypoints;  // lines 2..7 after "source:"
  const std::vector<BadCase> cases = {
      {"source:\n  frame_rat_hz: 20\n" + w, ":2: source.frame_rat_hz: unknown key"},
      {"source:\n  type: v4l2\n" + w, ":2: source.type: expected 'simulated'"},
      {"source:\n  frame_rate_hz: 0\n" + w, ":2: source.frame_rate_hz: must be in (0, 1000]"},
      {"source:\n  frame_rate_hz: fast\n" + w, ":2: source.frame_rate_hz: 'fast' is not a number"},
      {"source:\n  num_frames: 10\n  duration_s: 1\n" + w,
       ":3: source.duration_s: give either num_frames or duration_s"},
      {"source:\n  num_frames: 0\n" + w, ":2: source.num_frames: must be >= 1"},
      {"source:\n  num_frames: 200\n" + w,
       ":2: source.num_frames: 200 frames at 20 Hz last 9.95 s, longer than the trajectory (4 s)"},
      {"source:\n  seed: -1\n" + w, ":2: source.seed: must be >= 0"},
      {"source:\n  realtime: maybe\n" + w, ":2: source.realtime: expected true or false"},
      {"source:\n  noise_sigma: 200\n" + w, ":2: source.noise_sigma: must be in [0, 100]"},
      {"source:\n  motion_blur: true\n" + w, ":2: source.motion_blur: give {exposure_ms"},
      {"source:\n  motion_blur: {exposure_ms: 60}\n" + w,
       ":2: source.motion_blur.exposure_ms: must be in (0, 50) ms"},
      {"source:\n  motion_blur: {exposure_ms: 5, samples: 1}\n" + w,
       ":2: source.motion_blur.samples: must be in [2, 32]"},
      {"source:\n  motion_blur: {exposure_ms: 5, sample: 3}\n" + w,
       ":2: source.motion_blur.sample: unknown key"},
      {"source:\n  drop_probability: 1\n" + w, ":2: source.drop_probability: must be in [0, 1)"},
      {"source:\n  timestamp_jitter_ms: 9\n" + w,
       ":2: source.timestamp_jitter_ms: must be >= 0 with 3 sigma below half a frame period"},
      {"source:\n  fail_after_s: {cam1: -2}\n" + w, ":2: source.fail_after_s.cam1: must be >= 0"},
      {"source:\n  fail_after_s: [cam1]\n" + w, ":2: source.fail_after_s: expected a map"},
      {"source:\n  render_block: 0\n" + w, ":2: source.render_block: must be in [1, 32]"},
      {"source:\n  vignetting: 1\n" + w, ":2: source.vignetting: must be in [0, 1)"},
      {"source:\n  rolling_shutter_ms: -1\n" + w,
       ":2: source.rolling_shutter_ms: must be in [0, 50) ms"},
      {"source:\n  rolling_shutter_ms: 50\n" + w,
       ":2: source.rolling_shutter_ms: must be in [0, 50) ms"},
      {"source:\n  frame_rate_hz: 40\n  rolling_shutter_ms: 30\n" + w,
       ":3: source.rolling_shutter_ms: must be in [0, 25) ms"},
      {"source:\n  rolling_shutter_ms: slow\n" + w,
       ":2: source.rolling_shutter_ms: 'slow' is not a number"},
      {"source:\n  rolling_shutter_ms: [10]\n" + w, ":2: source.rolling_shutter_ms: "},
      {"source:\n  exposure_steps: {interval_s: 2}\n" + w,
       ":2: source.exposure_steps.max_factor: missing"},
      {"source:\n  exposure_steps: {interval_s: 0, max_factor: 2}\n" + w,
       ":2: source.exposure_steps.interval_s: must be > 0 s"},
      {"source:\n  exposure_steps: {interval_s: 1, max_factor: 0.5}\n" + w,
       ":2: source.exposure_steps.max_factor: must be in [1, 8]"},
      {"source:\n  exposure_steps: {interval_s: 1, max_factor: 2, step: 1}\n" + w,
       ":2: source.exposure_steps.step: unknown key"},
      {"source:\n  scene: {type: cave}\n" + w, ":2: source.scene.type: 'cave' is not a scene"},
      {"source:\n  scene:\n    type: room\n    diameter: 0.6\n" + w,
       ":4: source.scene.diameter: only for scene type pipe, not room"},
      {"source:\n  scene:\n    type: pipe\n    size: [1, 2, 3]\n" + w,
       ":4: source.scene.size: only for scene type room, yard or street, not pipe"},
      {"source:\n  scene: {size: [10, 0, 3]}\n" + w, ":2: source.scene.size: extents"},
      {"source:\n  scene: {boxes: 65}\n" + w, ":2: source.scene.boxes: must be in [0, 64]"},
      {"source:\n  scene:\n    moving_objects:\n      count: 65\n" + w,
       ":4: source.scene.moving_objects.count: must be in [0, 64]"},
      {"source:\n  scene:\n    moving_objects:\n      count: two\n" + w,
       ":4: source.scene.moving_objects.count: "},
      {"source:\n  scene:\n    moving_objects:\n      size: [1, 0, 2]\n" + w,
       ":4: source.scene.moving_objects.size: extents must be in (0, 100] m"},
      {"source:\n  scene:\n    moving_objects:\n      size: [1, 2]\n" + w,
       ":4: source.scene.moving_objects.size: expected 3 numbers, got 2"},
      {"source:\n  scene:\n    moving_objects:\n      speed_mps: 0\n" + w,
       ":4: source.scene.moving_objects.speed_mps: must be in (0, 100] m/s"},
      {"source:\n  scene:\n    moving_objects:\n      speed: 2\n" + w,
       ":4: source.scene.moving_objects.speed: unknown key"},
      {"source:\n  scene:\n    moving_objects: 3\n" + w,
       ":3: source.scene.moving_objects: expected {count"},
      {"source:\n  scene:\n    type: pipe\n    moving_objects: {count: 2}\n" + w,
       ":4: source.scene.moving_objects: only for scene type room, yard or street, not pipe"},
      {"source:\n  num_frames: 5\n", ":2: source.trajectory: missing"},
      {"source:\n  trajectory: {waypoint_interval_s: 1}\n",
       ":2: source.trajectory: give either `waypoints` or `file`"},
      {"source:\n  trajectory:\n    waypoints:\n      - {p: [0, 0, 1], ypr_deg: [0, 0, 0]}\n",
       ":4: source.trajectory.waypoints: expected a list of at least 2 waypoints"},
      {"source:\n  trajectory:\n    waypoints:\n      - {p: [0, 0, 1], ypr_deg: [0, 0, 0]}\n"
       "      - {p: [0, 0], ypr_deg: [0, 0, 0]}\n",
       ":5: source.trajectory.waypoints[1].p: expected 3 numbers, got 2"},
      {"source:\n  trajectory:\n    waypoints:\n      - {p: [0, 0, 1], ypr_deg: [0, 0, 0]}\n"
       "      - {p: [0, 0, 2]}\n",
       ":5: source.trajectory.waypoints[1]: give the orientation as either `ypr_deg` or `q_wxyz`"},
      {"source:\n  trajectory:\n    waypoints:\n      - {p: [0, 0, 1], ypr_deg: [0, 0, 0]}\n"
       "      - {p: [0, 0, 2], q_wxyz: [2, 0, 0, 0]}\n",
       ":5: source.trajectory.waypoints[1].q_wxyz: norm 2"},
      {"source:\n  trajectory:\n    waypoints:\n      - {p: [0, 0, 1], ypr_deg: [0, 0, 0]}\n"
       "      - {p: [0, 0, 2], ypr: [0, 0, 0]}\n",
       ":5: source.trajectory.waypoints[1].ypr: unknown key"},
      {"source:\n  trajectory:\n    waypoint_interval_s: -1\n    waypoints: []\n",
       ":3: source.trajectory.waypoint_interval_s: must be > 0"},
      {"source:\n  trajectory:\n    file: /nonexistent/traj.txt\n",
       ":3: source.trajectory.file: /nonexistent/traj.txt: cannot open"},
      {"source:\n  trajectory:\n    waypoints:\n      - {p: [0, 0, 1], ypr_deg: [0, 0, 0]}\n"
       "      - {p: [0, 0, 2], ypr_deg: [0, 0, 0]}\n    body_from_master: {q_wxyz: [1, 0, 0, 0], "
       "C: [0, 0, 0]}\n",
       ":6: source.trajectory.body_from_master: only with a trajectory `file`"},
  };
  for (const BadCase& c : cases) {
    std::string path;
    auto spec = Parse(c.text, &path);
    ASSERT_FALSE(spec) << c.text;
    EXPECT_NE(spec.error().find(c.expected), std::string::npos)
        << "expected '" << c.expected << "' in: " << spec.error();
    EXPECT_EQ(spec.error().rfind(path, 0), 0u) << spec.error();
  }
}

TEST(SimulatedSourceYaml, TrajectoryFileErrorsPointIntoBothFiles) {
  Write("bad.tum", "0.0 0 0 1 0 0 0 1\n1.0 1 0 1 0 0 0 1\n0.5 2 0 1 0 0 0 1\n");
  auto spec = Parse("source:\n  trajectory:\n    file: bad.tum\n");
  ASSERT_FALSE(spec);
  EXPECT_NE(spec.error().find(":3: source.trajectory.file: "), std::string::npos) << spec.error();
  EXPECT_NE(spec.error().find("bad.tum:3:"), std::string::npos) << spec.error();
}

// A whole rig config: the loader fills the cameras and checks the spec.
const char kRig[] =
    "rig: {master: cam0}\n"
    "cameras:\n"
    "  - name: cam0\n"
    "    model: pinhole\n"
    "    resolution: [64, 48]\n"
    "    intrinsics: [50, 50, 31.5, 23.5]\n"
    "  - name: cam1\n"
    "    model: pinhole\n"
    "    resolution: [64, 48]\n"
    "    intrinsics: [50, 50, 31.5, 23.5]\n"
    "    truth: {q_wxyz: [0.7071068, 0, 0.7071068, 0], C: [-0.5, 0, 0]}\n";

TEST(SimulatedSourceYaml, RigConfigFillsCamerasAndChecksTheSpec) {
  auto config = LoadRigConfig(
      Write("rig_ok.yaml", std::string(kRig) + "source:\n" + "  type: simulated\n" + kWaypoints));
  ASSERT_TRUE(config) << config.error();
  ASSERT_TRUE(config->simulated_source);
  const SimulatedRigSpec& spec = *config->simulated_source;
  EXPECT_EQ(spec.names, (std::vector<std::string>{"cam0", "cam1"}));
  ASSERT_EQ(spec.cameras.size(), 2u);
  EXPECT_EQ(spec.cameras[1]->width(), 64);
  EXPECT_DOUBLE_EQ(spec.master_from_camera[1].C.x(), -0.5);
  const Status status = spec.Check();
  EXPECT_TRUE(status.ok()) << status.message();
  EXPECT_TRUE(sim::MakeSimulatedRig(spec));

  auto unknown = LoadRigConfig(Write("rig_bad.yaml", std::string(kRig) +
                                                         "source:\n  type: simulated\n"
                                                         "  fail_after_s: {cam7: 1}\n" +
                                                         kWaypoints));
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.error().find("fail_after_s.cam7: no camera of that name"), std::string::npos)
      << unknown.error();
}

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct ShippedConfig {
  std::string file;
  enum class Motion { kGeneral, kPlanar, kAxial } motion;
};

// The shipped simulation configs load, keep every camera in free space, and move so that a VO
// can track (texture in view, image motion of a few to ~30 pixels per frame) and the
// calibration sees the rotations it needs (general: tens of degrees about varied axes;
// planar: yaw only; axial: a few degrees at most).
TEST(SimulatedConfigs, ShippedConfigsAreTrackable) {
  const std::vector<ShippedConfig> configs = {
      {"sim_thesis_virtual.yaml", ShippedConfig::Motion::kGeneral},
      {"sim_surround4.yaml", ShippedConfig::Motion::kPlanar},
      {"sim_spherical.yaml", ShippedConfig::Motion::kGeneral},
      {"sim_sewer.yaml", ShippedConfig::Motion::kAxial}};
  for (const ShippedConfig& shipped : configs) {
    SCOPED_TRACE(shipped.file);
    const std::string path = std::string(RIGCAL_SOURCE_DIR) + "/config/" + shipped.file;
    auto config = LoadRigConfig(path);
    ASSERT_TRUE(config) << config.error();
    ASSERT_TRUE(config->simulated_source);
    const SimulatedRigSpec& spec = *config->simulated_source;
    auto rig = sim::MakeSimulatedRig(spec);
    ASSERT_TRUE(rig) << rig.error();
    const int64_t frames = rig->num_frames();
    const int step = 5;

    // Rotation of the rig.
    double max_angle = 0.0;
    Eigen::Matrix3d axes = Eigen::Matrix3d::Zero();
    double max_tilt = 0.0, max_height_change = 0.0;
    const Pose first = rig->WorldFromMasterAt(0.0);
    for (int64_t k = 0; k + 20 < frames; k += step) {
      const Pose a = rig->WorldFromMasterAt(rig->FrameStreamTime(k));
      const Pose b = rig->WorldFromMasterAt(rig->FrameStreamTime(k + 20));
      max_angle = std::max(max_angle, first.q.angularDistance(a.q));
      const Eigen::AngleAxisd relative(a.q.conjugate() * b.q);
      const Eigen::Vector3d axis_world = a.q * relative.axis();
      axes += relative.angle() * axis_world * axis_world.transpose();
      // Planar: the camera's y axis (down) stays vertical, the height constant.
      max_tilt = std::max(max_tilt,
                          std::acos(std::clamp(-(a.q * Eigen::Vector3d::UnitY()).z(), -1.0, 1.0)));
      max_height_change = std::max(max_height_change, std::abs(a.C.z() - first.C.z()));
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(axes);
    const double axis_spread = eig.eigenvalues()(0) / eig.eigenvalues()(2);
    std::printf(
        "%s: %ld frames, largest rotation from the start %.1f deg, rotation axes spread "
        "%.3f, tilt %.2f deg, height change %.3f m\n",
        shipped.file.c_str(), static_cast<long>(frames), max_angle * 180 / M_PI, axis_spread,
        max_tilt * 180 / M_PI, max_height_change);
    switch (shipped.motion) {
      case ShippedConfig::Motion::kGeneral:
        EXPECT_GT(max_angle * 180 / M_PI, 25.0);
        EXPECT_GT(axis_spread, 0.05);  // rotations about varied axes
        break;
      case ShippedConfig::Motion::kPlanar:
        EXPECT_LT(max_tilt * 180 / M_PI, 1e-4);
        EXPECT_LT(max_height_change, 1e-9);
        EXPECT_GT(max_angle * 180 / M_PI, 90.0);
        break;
      case ShippedConfig::Motion::kAxial:
        EXPECT_LT(max_angle * 180 / M_PI, 10.0);
        break;
    }

    // Image motion: points seen at frame k, projected into frame k + 1.
    for (int c = 0; c < rig->num_cameras(); ++c) {
      const camera::CameraModel& model = *spec.cameras[c];
      std::vector<double> flow;
      int valid = 0, hit = 0;
      for (int64_t k = 0; k + 1 < frames; k += 4 * step) {
        const Pose a = rig->WorldFromCameraAt(c, rig->FrameStreamTime(k));
        const Pose b = rig->WorldFromCameraAt(c, rig->FrameStreamTime(k + 1));
        for (int y = 8; y < model.height(); y += 24) {
          for (int x = 8; x < model.width(); x += 24) {
            const auto bearing = model.Unproject(Eigen::Vector2d(x, y));
            if (!bearing) continue;
            ++valid;
            const Eigen::Vector3d d = a.R() * *bearing;
            const auto t = rig->CastRay(a.C, d);
            if (!t) continue;
            ++hit;
            const auto px = model.Project(b.R().transpose() * (a.C + *t * d - b.C));
            if (px) flow.push_back((*px - Eigen::Vector2d(x, y)).norm());
          }
        }
      }
      const double median = Quantile(flow, 0.5), p95 = Quantile(flow, 0.95);
      const double hit_fraction = static_cast<double>(hit) / std::max(valid, 1);
      std::printf(
          "  %-6s texture in %.0f%% of the view, flow per frame: median %.1f px, 95%% "
          "%.1f px, max %.1f px\n",
          spec.names[c].c_str(), 100 * hit_fraction, median, p95, Quantile(flow, 1.0));
      EXPECT_GT(hit_fraction, 0.5) << spec.names[c];
      EXPECT_GT(median, 0.3) << spec.names[c];
      EXPECT_LT(p95, 35.0) << spec.names[c];
    }

    // The images agree with the configured camera models: a pixel of frame k and the
    // projection into frame k + 3 of the point it sees show the same texture (and a projection
    // off by 2 px does not).
    for (int c = 0; c < rig->num_cameras(); ++c) {
      const camera::CameraModel& model = *spec.cameras[c];
      double sum = 0, sum_off = 0;
      int n = 0;
      for (int64_t k = frames / 3; k + 3 < frames; k += frames / 3) {
        const Pose a = rig->WorldFromCameraAt(c, rig->FrameStreamTime(k));
        const Pose b = rig->WorldFromCameraAt(c, rig->FrameStreamTime(k + 3));
        const cv::Mat image_a = rig->RenderView(c, a);
        const cv::Mat image_b = rig->RenderView(c, b);
        for (int y = 10; y < model.height() - 10; y += 5) {
          for (int x = 10; x < model.width() - 10; x += 5) {
            const auto bearing = model.Unproject(Eigen::Vector2d(x, y));
            if (!bearing) continue;
            const Eigen::Vector3d d = a.R() * *bearing;
            const auto t = rig->CastRay(a.C, d);
            if (!t) continue;
            const Eigen::Vector3d to_point = a.C + *t * d - b.C;
            const auto t_b = rig->CastRay(b.C, to_point);
            if (!t_b || std::abs(*t_b - 1.0) > 1e-6) continue;  // hidden in frame k + 3
            const auto px = model.Project(b.R().transpose() * to_point);
            if (!px || !model.InImage(*px, 12.0)) continue;
            auto at = [&](const Eigen::Vector2d& p) {
              const int x0 = static_cast<int>(std::floor(p.x())),
                        y0 = static_cast<int>(std::floor(p.y()));
              const double ax = p.x() - x0, ay = p.y() - y0;
              auto v = [&](int xx, int yy) {
                return static_cast<double>(image_b.at<uint8_t>(yy, xx));
              };
              return (1 - ay) * ((1 - ax) * v(x0, y0) + ax * v(x0 + 1, y0)) +
                     ay * ((1 - ax) * v(x0, y0 + 1) + ax * v(x0 + 1, y0 + 1));
            };
            const double value = image_a.at<uint8_t>(y, x);
            sum += std::abs(value - at(*px));
            sum_off += std::abs(value - at(*px + Eigen::Vector2d(2.0, 0.0)));
            ++n;
          }
        }
      }
      std::printf(
          "  %-6s registration through the camera model: %.2f grey levels (%d points), "
          "2 px off: %.2f\n",
          spec.names[c].c_str(), sum / n, n, sum_off / n);
      ASSERT_GT(n, 500) << spec.names[c];
      EXPECT_LT(sum / n, 0.5 * sum_off / n) << spec.names[c];
    }

    // Render cost (no assertion: printed for the record).
    const int render_frames = 10;
    const double start = ThreadCpuSeconds();
    for (int k = 0; k < render_frames; ++k) {
      (void)rig->RenderFrame(k % rig->num_cameras(), k * frames / render_frames);
    }
    std::printf("  render: %.2f ms CPU per frame (%d x %d)\n",
                (ThreadCpuSeconds() - start) * 1e3 / render_frames, spec.cameras[0]->width(),
                spec.cameras[0]->height());
  }
}

}  // namespace
}  // namespace rigcal::io
