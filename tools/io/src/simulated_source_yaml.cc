// SPDX-License-Identifier: Apache-2.0
// The `source:` section of type `simulated` (keys documented in
// drivers/sim/include/rigcal/sim/simulated_rig.h): fills sim::SimulatedRigSpec, with
// errors that name the line and key. Cameras and their true mounting are the caller's
// (`cameras:` of the rig config).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "config_sections.h"
#include "rigcal/base/format.h"
#include "rigcal/io/trajectory_io.h"
#include "yaml_fields.h"

namespace rigcal::io {
namespace {

using sim::SimulatedRigSpec;

const std::set<std::string> kSourceKeys = {
    "type",         "frame_rate_hz", "num_frames",       "duration_s",
    "seed",         "realtime",      "trajectory",       "scene",
    "noise_sigma",  "motion_blur",   "drop_probability", "timestamp_jitter_ms",
    "fail_after_s", "blackout_s",    "render_block",     "trigger",
    "blur_burst_s", "vignetting",    "exposure_steps",   "rolling_shutter_ms"};

// A number as people write it: "20", "9.95", "8.33333".
std::string PlainNumber(double v) { return SignificantText(v, 6); }

// The key node of `key` in map `map` (its line is the line of "key:"), or `map` itself.
YAML::Node KeyOf(const YAML::Node& map, const std::string& key) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (it->first.Scalar() == key) return it->first;
  }
  return map;
}

// A number at `node` that satisfies `ok`; `range` describes the constraint for the message.
template <typename Predicate>
Expected<double> NumberIn(const FieldReader& r, const YAML::Node& node, const std::string& field,
                          Predicate ok, const std::string& range) {
  auto v = r.Number(node, field);
  if (!v) return v;
  if (!ok(*v)) return r.Fail(node, field, "must be " + range);
  return v;
}

// A unit quaternion [w, x, y, z]: hand-typed values within 1e-3 of unit norm are normalised.
Expected<Eigen::Quaterniond> Quaternion(const FieldReader& r, const YAML::Node& node,
                                        const std::string& field) {
  auto q = r.NumbersOf(node, field, 4);
  if (!q) return Error{q.error()};
  Eigen::Quaterniond quaternion((*q)[0], (*q)[1], (*q)[2], (*q)[3]);
  const double norm = quaternion.norm();
  if (std::abs(norm - 1.0) > 1e-3) {
    return r.Fail(node, field, "norm " + PlainNumber(norm) + " is not 1 (within 1e-3)");
  }
  return quaternion.normalized();
}

// {q_wxyz, C}: a pose.
Expected<Pose> ReadPose(const FieldReader& r, const YAML::Node& node, const std::string& field) {
  if (auto e = r.CheckKeys(node, field + ".", {"q_wxyz", "C"})) return *e;
  if (!node["q_wxyz"]) return r.Fail(node, field + ".q_wxyz", "missing");
  auto q = Quaternion(r, node["q_wxyz"], field + ".q_wxyz");
  if (!q) return Error{q.error()};
  auto c = r.Numbers(node, "C", field + ".C", 3);
  if (!c) return Error{c.error()};
  Pose pose;
  pose.q = *q;
  pose.C = Eigen::Vector3d((*c)[0], (*c)[1], (*c)[2]);
  return pose;
}

std::optional<Error> ReadTrajectorySection(const FieldReader& r, const YAML::Node& node,
                                           const std::string& path, SimulatedRigSpec* spec) {
  const std::string prefix = "source.trajectory";
  if (auto e = r.CheckKeys(node, prefix + ".",
                           {"waypoint_interval_s", "waypoints", "file", "body_from_master"})) {
    return *e;
  }
  const YAML::Node waypoints = node["waypoints"];
  const YAML::Node file = node["file"];
  if (static_cast<bool>(waypoints) == static_cast<bool>(file)) {
    return r.Fail(node, prefix, "give either `waypoints` or `file`");
  }
  if (waypoints) {
    if (node["body_from_master"]) {
      return r.Fail(KeyOf(node, "body_from_master"), prefix + ".body_from_master",
                    "only with a trajectory `file`");
    }
    if (const YAML::Node n = node["waypoint_interval_s"]) {
      auto v = NumberIn(
          r, n, prefix + ".waypoint_interval_s", [](double x) { return x > 0; }, "> 0 s");
      if (!v) return Error{v.error()};
      spec->waypoint_interval_s = *v;
    }
    if (!waypoints.IsSequence() || waypoints.size() < 2) {
      return r.Fail(waypoints, prefix + ".waypoints", "expected a list of at least 2 waypoints");
    }
    for (size_t i = 0; i < waypoints.size(); ++i) {
      const YAML::Node w = waypoints[i];
      const std::string field = prefix + ".waypoints[" + std::to_string(i) + "]";
      if (auto e = r.CheckKeys(w, field + ".", {"p", "ypr_deg", "q_wxyz"})) return *e;
      SimulatedRigSpec::Waypoint waypoint;
      auto p = r.Numbers(w, "p", field + ".p", 3);
      if (!p) return Error{p.error()};
      waypoint.position = Eigen::Vector3d((*p)[0], (*p)[1], (*p)[2]);
      if (static_cast<bool>(w["ypr_deg"]) == static_cast<bool>(w["q_wxyz"])) {
        return r.Fail(w, field, "give the orientation as either `ypr_deg` or `q_wxyz`");
      }
      if (w["ypr_deg"]) {
        auto ypr = r.NumbersOf(w["ypr_deg"], field + ".ypr_deg", 3);
        if (!ypr) return Error{ypr.error()};
        waypoint.world_from_master =
            sim::WaypointOrientationFromYpr((*ypr)[0], (*ypr)[1], (*ypr)[2]);
      } else {
        auto q = Quaternion(r, w["q_wxyz"], field + ".q_wxyz");
        if (!q) return Error{q.error()};
        waypoint.world_from_master = *q;
      }
      spec->waypoints.push_back(waypoint);
    }
    return std::nullopt;
  }
  if (node["waypoint_interval_s"]) {
    return r.Fail(KeyOf(node, "waypoint_interval_s"), prefix + ".waypoint_interval_s",
                  "only with `waypoints`");
  }
  auto name = r.String(file, prefix + ".file");
  if (!name) return Error{name.error()};
  namespace fs = std::filesystem;
  fs::path file_path(*name);
  if (file_path.is_relative()) file_path = fs::path(path).parent_path() / file_path;
  auto trajectory = ReadTrajectory(file_path.string());
  if (!trajectory) return r.Fail(file, prefix + ".file", trajectory.error());
  if (trajectory->size() < 2) {
    return r.Fail(file, prefix + ".file", file_path.string() + ": needs at least 2 poses");
  }
  spec->trajectory_file = file_path.string();
  spec->trajectory_t_ns = trajectory->t_ns;
  spec->trajectory_world_from_body = trajectory->poses;
  if (const YAML::Node n = node["body_from_master"]) {
    auto pose = ReadPose(r, n, prefix + ".body_from_master");
    if (!pose) return Error{pose.error()};
    spec->body_from_master = *pose;
  }
  return std::nullopt;
}

// One photograph of source.scene.textures, as 8-bit grey (colour averaged, 16 bit scaled).
Expected<SimulatedRigSpec::GreyImage> ReadTexturePhoto(const std::string& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) return Error{file + ": no such file"};
  const cv::Mat image = cv::imread(file, cv::IMREAD_GRAYSCALE);
  if (image.empty()) return Error{file + ": not a readable image"};
  if (image.cols < sim::kMinTextureImagePx || image.rows < sim::kMinTextureImagePx) {
    return Error{file + ": " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                 " px, needs at least " + std::to_string(sim::kMinTextureImagePx) + " px a side"};
  }
  SimulatedRigSpec::GreyImage photo;
  photo.name = file;
  photo.width = image.cols;
  photo.height = image.rows;
  photo.pixels.resize(image.total());
  for (int y = 0; y < image.rows; ++y) {
    std::copy(image.ptr<uint8_t>(y), image.ptr<uint8_t>(y) + image.cols,
              photo.pixels.begin() + static_cast<std::ptrdiff_t>(y) * image.cols);
  }
  return photo;
}

// source.scene.textures: a list of image files, relative to the config file's folder.
std::optional<Error> ReadTextures(const FieldReader& r, const YAML::Node& node,
                                  const std::string& path, SimulatedRigSpec::Scene* scene) {
  const std::string field = "source.scene.textures";
  if (!node.IsSequence() || node.size() == 0) {
    return r.Fail(node, field, "must be a non-empty list of image files");
  }
  for (size_t i = 0; i < node.size(); ++i) {
    const std::string item = field + "[" + std::to_string(i) + "]";
    auto name = r.String(node[i], item);
    if (!name) return Error{name.error()};
    std::filesystem::path file(*name);
    if (file.is_relative()) file = std::filesystem::path(path).parent_path() / file;
    auto photo = ReadTexturePhoto(file.string());
    if (!photo) return r.Fail(node[i], item, photo.error());
    scene->textures.push_back(std::move(*photo));
  }
  return std::nullopt;
}

// source.scene.moving_objects: {count, size, speed_mps}, each optional.
std::optional<Error> ReadMovingObjects(const FieldReader& r, const YAML::Node& node,
                                       SimulatedRigSpec::Scene::MovingObjects* moving) {
  const std::string prefix = "source.scene.moving_objects";
  if (!node.IsMap()) {
    return r.Fail(node, prefix, "expected {count: ..., size: ..., speed_mps: ...}");
  }
  if (auto e = r.CheckKeys(node, prefix + ".", {"count", "size", "speed_mps"})) return *e;
  if (const YAML::Node n = node["count"]) {
    auto count = r.Integer(n, prefix + ".count");
    if (!count) return Error{count.error()};
    if (*count < 0 || *count > 64) return r.Fail(n, prefix + ".count", "must be in [0, 64]");
    moving->count = *count;
  }
  if (const YAML::Node n = node["size"]) {
    auto size = r.NumbersOf(n, prefix + ".size", 3);
    if (!size) return Error{size.error()};
    for (double v : *size) {
      if (!(v > 0 && v <= 100)) return r.Fail(n, prefix + ".size", "extents must be in (0, 100] m");
    }
    moving->size_m = Eigen::Vector3d((*size)[0], (*size)[1], (*size)[2]);
  }
  if (const YAML::Node n = node["speed_mps"]) {
    auto v = NumberIn(
        r, n, prefix + ".speed_mps", [](double x) { return x > 0 && x <= 100; }, "in (0, 100] m/s");
    if (!v) return Error{v.error()};
    moving->speed_mps = *v;
  }
  return std::nullopt;
}

std::optional<Error> ReadSceneSection(const FieldReader& r, const YAML::Node& node,
                                      const std::string& path, SimulatedRigSpec* spec) {
  const std::string prefix = "source.scene";
  if (auto e = r.CheckKeys(node, prefix + ".",
                           {"type", "size", "boxes", "diameter", "length", "texel_m", "textures",
                            "moving_objects"})) {
    return *e;
  }
  SimulatedRigSpec::Scene& scene = spec->scene;
  if (const YAML::Node n = node["type"]) {
    auto text = r.String(n, prefix + ".type");
    if (!text) return Error{text.error()};
    const auto type = sim::SceneTypeFromString(*text);
    if (!type) {
      return r.Fail(n, prefix + ".type",
                    "'" + *text + "' is not a scene (expected room, yard, street or pipe)");
    }
    scene.type = *type;
  }
  const bool pipe = scene.type == SimulatedRigSpec::SceneType::kPipe;
  const std::string type_name = sim::ToString(scene.type);
  auto only = [&](const std::string& key, bool allowed, const std::string& types) {
    return allowed ? std::nullopt
                   : std::optional<Error>(
                         r.Fail(KeyOf(node, key), prefix + "." + key,
                                "only for scene type " + types + ", not " + type_name));
  };
  if (const YAML::Node n = node["size"]) {
    if (auto e = only("size", !pipe, "room, yard or street")) return *e;
    auto size = r.NumbersOf(n, prefix + ".size", 3);
    if (!size) return Error{size.error()};
    for (double v : *size) {
      if (!(v > 0 && v <= 100000)) {
        return r.Fail(n, prefix + ".size", "extents must be in (0, 100000] m");
      }
    }
    scene.size = Eigen::Vector3d((*size)[0], (*size)[1], (*size)[2]);
  }
  if (const YAML::Node n = node["boxes"]) {
    if (auto e = only("boxes", !pipe, "room, yard or street")) return *e;
    auto boxes = r.Integer(n, prefix + ".boxes");
    if (!boxes) return Error{boxes.error()};
    if (*boxes < 0 || *boxes > 64) return r.Fail(n, prefix + ".boxes", "must be in [0, 64]");
    scene.boxes = *boxes;
  }
  if (const YAML::Node n = node["diameter"]) {
    if (auto e = only("diameter", pipe, "pipe")) return *e;
    auto v = NumberIn(
        r, n, prefix + ".diameter", [](double x) { return x > 0 && x <= 1000; }, "in (0, 1000] m");
    if (!v) return Error{v.error()};
    scene.pipe_diameter = *v;
  }
  if (const YAML::Node n = node["length"]) {
    if (auto e = only("length", pipe, "pipe")) return *e;
    auto v = NumberIn(
        r, n, prefix + ".length", [](double x) { return x > 0 && x <= 100000; },
        "in (0, 100000] m");
    if (!v) return Error{v.error()};
    scene.pipe_length = *v;
  }
  if (const YAML::Node n = node["texel_m"]) {
    auto v = NumberIn(
        r, n, prefix + ".texel_m", [](double x) { return x > 0 && x <= 10; }, "in (0, 10] m");
    if (!v) return Error{v.error()};
    scene.texel_m = *v;
  }
  if (const YAML::Node n = node["textures"]) {
    if (auto e = ReadTextures(r, n, path, &scene)) return *e;
  }
  if (const YAML::Node n = node["moving_objects"]) {
    if (auto e = only("moving_objects", !pipe, "room, yard or street")) return *e;
    if (auto e = ReadMovingObjects(r, n, &scene.moving_objects)) return *e;
  }
  return std::nullopt;
}

// frame_rate_hz, num_frames / duration_s, seed, realtime.
std::optional<Error> ReadTiming(const FieldReader& r, const YAML::Node& source,
                                SimulatedRigSpec* spec) {
  if (const YAML::Node n = source["frame_rate_hz"]) {
    auto v = NumberIn(
        r, n, "source.frame_rate_hz", [](double x) { return x > 0 && x <= 1000; },
        "in (0, 1000] Hz");
    if (!v) return Error{v.error()};
    spec->frame_rate_hz = *v;
  }
  if (source["num_frames"] && source["duration_s"]) {
    return r.Fail(KeyOf(source, "duration_s"), "source.duration_s",
                  "give either num_frames or duration_s, not both");
  }
  if (const YAML::Node n = source["num_frames"]) {
    auto v = r.Integer64(n, "source.num_frames");
    if (!v) return Error{v.error()};
    if (*v < 1) return r.Fail(n, "source.num_frames", "must be >= 1");
    spec->num_frames = *v;
  }
  if (const YAML::Node n = source["duration_s"]) {
    auto v = NumberIn(
        r, n, "source.duration_s", [](double x) { return x > 0; }, "> 0 s");
    if (!v) return Error{v.error()};
    spec->duration_s = *v;
  }
  if (const YAML::Node n = source["seed"]) {
    auto v = r.Integer64(n, "source.seed");
    if (!v) return Error{v.error()};
    if (*v < 0) return r.Fail(n, "source.seed", "must be >= 0");
    spec->seed = static_cast<uint64_t>(*v);
  }
  if (const YAML::Node n = source["realtime"]) {
    auto v = r.Bool(n, "source.realtime");
    if (!v) return Error{v.error()};
    spec->realtime = *v;
  }
  return std::nullopt;
}

// noise_sigma, motion_blur, rolling_shutter_ms, drop_probability, timestamp_jitter_ms.
std::optional<Error> ReadImageEffects(const FieldReader& r, const YAML::Node& source,
                                      SimulatedRigSpec* spec) {
  const double period_s = 1.0 / spec->frame_rate_hz;
  if (const YAML::Node n = source["noise_sigma"]) {
    auto v = NumberIn(
        r, n, "source.noise_sigma", [](double x) { return x >= 0 && x <= 100; },
        "in [0, 100] grey levels");
    if (!v) return Error{v.error()};
    spec->noise_sigma = *v;
  }
  if (const YAML::Node n = source["motion_blur"]) {
    if (n.IsScalar()) {
      auto on = r.Bool(n, "source.motion_blur");
      if (!on) return Error{on.error()};
      if (*on) {
        return r.Fail(n, "source.motion_blur",
                      "give {exposure_ms: ..., samples: ...} to turn it on, or false");
      }
    } else {
      if (auto e = r.CheckKeys(n, "source.motion_blur.", {"exposure_ms", "samples"})) return *e;
      if (!n["exposure_ms"]) return r.Fail(n, "source.motion_blur.exposure_ms", "missing");
      auto exposure = NumberIn(
          r, n["exposure_ms"], "source.motion_blur.exposure_ms",
          [&](double x) { return x > 0 && x * 1e-3 < period_s; },
          "in (0, " + PlainNumber(period_s * 1e3) + ") ms (shorter than a frame period)");
      if (!exposure) return Error{exposure.error()};
      spec->blur_exposure_s = *exposure * 1e-3;
      if (const YAML::Node s = n["samples"]) {
        auto samples = r.Integer(s, "source.motion_blur.samples");
        if (!samples) return Error{samples.error()};
        if (*samples < 2 || *samples > 32) {
          return r.Fail(s, "source.motion_blur.samples", "must be in [2, 32]");
        }
        spec->blur_samples = *samples;
      }
    }
  }
  if (const YAML::Node n = source["rolling_shutter_ms"]) {
    auto v = NumberIn(
        r, n, "source.rolling_shutter_ms", [&](double x) { return x >= 0 && x * 1e-3 < period_s; },
        "in [0, " + PlainNumber(period_s * 1e3) + ") ms (row readout shorter than a frame period)");
    if (!v) return Error{v.error()};
    spec->rolling_shutter_s = *v * 1e-3;
  }
  if (const YAML::Node n = source["drop_probability"]) {
    auto v = NumberIn(
        r, n, "source.drop_probability", [](double x) { return x >= 0 && x < 1; }, "in [0, 1)");
    if (!v) return Error{v.error()};
    spec->drop_probability = *v;
  }
  if (const YAML::Node n = source["timestamp_jitter_ms"]) {
    auto v = NumberIn(
        r, n, "source.timestamp_jitter_ms",
        [&](double x) { return x >= 0 && 3 * x * 1e-3 < 0.5 * period_s; },
        ">= 0 with 3 sigma below half a frame period (< " + PlainNumber(period_s * 1e3 / 6) +
            " ms)");
    if (!v) return Error{v.error()};
    spec->timestamp_jitter_s = *v * 1e-3;
  }
  return std::nullopt;
}

// vignetting, exposure_steps: the light the camera gathers.
std::optional<Error> ReadExposure(const FieldReader& r, const YAML::Node& source,
                                  SimulatedRigSpec* spec) {
  if (const YAML::Node n = source["vignetting"]) {
    auto v = NumberIn(
        r, n, "source.vignetting", [](double x) { return x >= 0 && x < 1; },
        "in [0, 1) (the corner's light falls to 1 - x of the centre's)");
    if (!v) return Error{v.error()};
    spec->vignetting = *v;
  }
  if (const YAML::Node n = source["exposure_steps"]) {
    if (auto e = r.CheckKeys(n, "source.exposure_steps.", {"interval_s", "max_factor"})) return *e;
    if (!n["interval_s"]) return r.Fail(n, "source.exposure_steps.interval_s", "missing");
    if (!n["max_factor"]) return r.Fail(n, "source.exposure_steps.max_factor", "missing");
    auto interval = NumberIn(
        r, n["interval_s"], "source.exposure_steps.interval_s", [](double x) { return x > 0; },
        "> 0 s");
    if (!interval) return Error{interval.error()};
    auto factor = NumberIn(
        r, n["max_factor"], "source.exposure_steps.max_factor",
        [](double x) { return x >= 1 && x <= 8; }, "in [1, 8]");
    if (!factor) return Error{factor.error()};
    spec->exposure_steps.interval_s = *interval;
    spec->exposure_steps.max_factor = *factor;
  }
  return std::nullopt;
}

// `trigger:`: the simulated hardware trigger.
std::optional<Error> ReadSimulatedTrigger(const FieldReader& r, const YAML::Node& source,
                                          SimulatedRigSpec* spec) {
  if (const YAML::Node n = source["trigger"]) {  // simulated hardware trigger
    if (auto e =
            r.CheckKeys(n, "source.trigger.",
                        {"drift_ppm", "link_jitter_ms", "exposure_ms", "corrupt_probability"})) {
      return *e;
    }
    spec->trigger.enabled = true;
    struct Field {
      const char* key;
      double* value;
      double lo, hi;
    };
    for (const Field& f :
         {Field{"drift_ppm", &spec->trigger.drift_ppm, -1000, 1000},
          Field{"link_jitter_ms", &spec->trigger.link_jitter_ms, 0, 20},
          Field{"exposure_ms", &spec->trigger.exposure_ms, 0, 1000},
          Field{"corrupt_probability", &spec->trigger.corrupt_probability, 0, 0.01}}) {
      if (const YAML::Node v = n[f.key]) {
        auto x = NumberIn(
            r, v, std::string("source.trigger.") + f.key,
            [&](double y) { return y >= f.lo && y <= f.hi; },
            "in [" + PlainNumber(f.lo) + ", " + PlainNumber(f.hi) + "]");
        if (!x) return Error{x.error()};
        *f.value = *x;
      }
    }
  }
  return std::nullopt;
}

// blackout_s (a span of stream time [from, to) in which it sees nothing) or blur_burst_s (in
// which its frames are blurred): per camera, `name` of `source`, into `spans`.
std::optional<Error> ReadSpans(const FieldReader& r, const YAML::Node& source,
                               const std::string& name,
                               std::map<std::string, std::pair<double, double>>* spans) {
  if (const YAML::Node n = source[name]) {
    if (!n.IsMap()) return r.Fail(n, "source." + name, "expected a map camera: [from, to]");
    for (auto it = n.begin(); it != n.end(); ++it) {
      const std::string key = "source." + name + "." + it->first.Scalar();
      if (!it->second.IsSequence() || it->second.size() != 2) {
        return r.Fail(it->second, key, "expected [from, to] in seconds");
      }
      auto from = NumberIn(
          r, it->second[0], key, [](double x) { return x >= 0; }, ">= 0 s");
      if (!from) return Error{from.error()};
      auto to = NumberIn(
          r, it->second[1], key, [&](double x) { return x > *from; }, "> from");
      if (!to) return Error{to.error()};
      (*spans)[it->first.Scalar()] = {*from, *to};
    }
  }
  return std::nullopt;
}

// fail_after_s, render_block.
std::optional<Error> ReadFailuresAndRendering(const FieldReader& r, const YAML::Node& source,
                                              SimulatedRigSpec* spec) {
  if (const YAML::Node n = source["fail_after_s"]) {
    if (!n.IsMap()) return r.Fail(n, "source.fail_after_s", "expected a map camera: seconds");
    for (auto it = n.begin(); it != n.end(); ++it) {
      const std::string camera = it->first.Scalar();
      auto v = NumberIn(
          r, it->second, "source.fail_after_s." + camera, [](double x) { return x >= 0; },
          ">= 0 s");
      if (!v) return Error{v.error()};
      spec->fail_after_s[camera] = *v;
    }
  }
  if (const YAML::Node n = source["render_block"]) {
    auto v = r.Integer(n, "source.render_block");
    if (!v) return Error{v.error()};
    if (*v < 1 || *v > 32) return r.Fail(n, "source.render_block", "must be in [1, 32]");
    spec->render_block = *v;
  }
  return std::nullopt;
}

// The frames must fit into the trajectory.
std::optional<Error> CheckFramesFitTrajectory(const FieldReader& r, const YAML::Node& source,
                                              const SimulatedRigSpec* spec) {
  const double period_s = 1.0 / spec->frame_rate_hz;
  double duration = 0.0;
  if (!spec->waypoints.empty()) {
    duration = static_cast<double>(spec->waypoints.size() - 1) * spec->waypoint_interval_s;
  } else {
    duration =
        static_cast<double>(spec->trajectory_t_ns.back() - spec->trajectory_t_ns.front()) * 1e-9;
  }
  const int64_t frames = spec->num_frames > 0 ? spec->num_frames
                         : spec->duration_s > 0
                             ? std::llround(spec->duration_s * spec->frame_rate_hz)
                             : 0;
  if (frames > 0 && static_cast<double>(frames - 1) * period_s > duration + 1e-6) {
    const std::string key = spec->num_frames > 0 ? "num_frames" : "duration_s";
    return r.Fail(source[key], "source." + key,
                  std::to_string(frames) + " frames at " + PlainNumber(spec->frame_rate_hz) +
                      " Hz last " + PlainNumber(static_cast<double>(frames - 1) * period_s) +
                      " s, longer than the trajectory (" + PlainNumber(duration) + " s)");
  }
  return std::nullopt;
}

}  // namespace

Expected<sim::SimulatedRigSpec> ParseSimulatedSource(const YAML::Node& source,
                                                     const std::string& path) {
  const FieldReader r(path);
  if (auto e = r.CheckKeys(source, "source.", kSourceKeys)) return *e;
  SimulatedRigSpec spec;
  if (const YAML::Node n = source["type"]) {
    auto type = r.String(n, "source.type");
    if (!type) return Error{type.error()};
    if (*type != "simulated") return r.Fail(n, "source.type", "expected 'simulated'");
  }
  if (auto e = ReadTiming(r, source, &spec)) return *e;
  const YAML::Node trajectory = source["trajectory"];
  if (!trajectory) return r.Fail(source, "source.trajectory", "missing (waypoints or a file)");
  if (auto e = ReadTrajectorySection(r, trajectory, path, &spec)) return *e;
  if (const YAML::Node n = source["scene"]) {
    if (auto e = ReadSceneSection(r, n, path, &spec)) return *e;
  }
  if (auto e = ReadImageEffects(r, source, &spec)) return *e;
  if (auto e = ReadExposure(r, source, &spec)) return *e;
  if (auto e = ReadSimulatedTrigger(r, source, &spec)) return *e;
  if (auto e = ReadFailuresAndRendering(r, source, &spec)) return *e;
  if (auto e = ReadSpans(r, source, "blackout_s", &spec.blackout_s)) return *e;
  if (auto e = ReadSpans(r, source, "blur_burst_s", &spec.blur_burst_s)) return *e;
  if (auto e = CheckFramesFitTrajectory(r, source, &spec)) return *e;
  return spec;
}

}  // namespace rigcal::io
