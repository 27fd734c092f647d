// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/rig_config.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <set>

#include "config_sections.h"
#include "rig_config_yaml.h"
#include "trigger_yaml.h"
#include "yaml_fields.h"

namespace rigcal::io {
namespace {

// Keys of a camera entry read here; the camera section parser reads the others.
const std::set<std::string> kCameraOwnKeys = {"name",    "nominal", "truth", "device",
                                              "capture", "trigger", "metric"};

Expected<Similarity> ParseMounting(const FieldReader& r, const YAML::Node& node,
                                   const std::string& field) {
  if (auto e = r.CheckKeys(node, field + ".", {"q_wxyz", "C", "scale"})) return *e;
  Similarity mounting;
  auto q = r.UnitQuaternion(node, "q_wxyz", field + ".q_wxyz");
  if (!q) return Error{q.error()};
  mounting.q = *q;
  auto c = r.Numbers(node, "C", field + ".C", 3);
  if (!c) return Error{c.error()};
  mounting.C = Eigen::Vector3d((*c)[0], (*c)[1], (*c)[2]);
  if (const YAML::Node scale = node["scale"]) {
    auto s = r.Number(scale, field + ".scale");
    if (!s) return Error{s.error()};
    if (!(*s > 0.0)) return r.Fail(scale, field + ".scale", "must be > 0");
    mounting.scale = *s;
  }
  return mounting;
}

Expected<CameraConfig> ParseCamera(const FieldReader& r, const YAML::Node& node,
                                   const std::string& path, size_t index) {
  const std::string field = "cameras[" + std::to_string(index) + "]";
  if (!node.IsMap()) return r.Fail(node, field, "expected a map with at least `name`");
  CameraConfig camera;
  if (!node["name"]) return r.Fail(node, field + ".name", "missing");
  auto name = r.CameraName(node["name"], field + ".name");
  if (!name) return Error{name.error()};
  camera.name = *name;
  bool has_intrinsics = false;
  for (auto it = node.begin(); it != node.end(); ++it) {
    if (kCameraOwnKeys.count(it->first.Scalar()) == 0) has_intrinsics = true;
  }
  if (has_intrinsics) {
    auto spec = ParseCameraSection(node, path);
    if (!spec) return Error{spec.error()};
    camera.spec = std::move(*spec);
  }
  if (const YAML::Node nominal = node["nominal"]) {
    auto mounting = ParseMounting(r, nominal, camera.name + ".nominal");
    if (!mounting) return Error{mounting.error()};
    camera.nominal = *mounting;
  }
  if (const YAML::Node truth = node["truth"]) {
    auto mounting = ParseMounting(r, truth, camera.name + ".truth");
    if (!mounting) return Error{mounting.error()};
    camera.truth = *mounting;
  }
  if (const YAML::Node device = node["device"]) {
    auto text = r.String(device, camera.name + ".device");
    if (!text) return Error{text.error()};
    camera.device = *text;
  }
  if (const YAML::Node metric = node["metric"]) {
    if (!metric.IsScalar() || (metric.Scalar() != "true" && metric.Scalar() != "false")) {
      return r.Fail(metric, camera.name + ".metric", "expected true or false");
    }
    camera.metric = metric.Scalar() == "true";
  }
  return camera;
}

// Setters of RigEstimatorOptions / OnlineOptions fields by their name in the `estimator:` map.
using FieldSetter = std::function<std::optional<Error>(const FieldReader&, const YAML::Node&,
                                                       const std::string&, OnlineOptions*)>;

FieldSetter Double(double RigEstimatorOptions::*member) {
  return [member](const FieldReader& r, const YAML::Node& node, const std::string& field,
                  OnlineOptions* options) -> std::optional<Error> {
    auto v = r.Number(node, field);
    if (!v) return Error{v.error()};
    options->estimator.*member = *v;
    return std::nullopt;
  };
}

FieldSetter Double(double ModelSelectionOptions::*member) {
  return [member](const FieldReader& r, const YAML::Node& node, const std::string& field,
                  OnlineOptions* options) -> std::optional<Error> {
    auto v = r.Number(node, field);
    if (!v) return Error{v.error()};
    options->estimator.model_selection.*member = *v;
    return std::nullopt;
  };
}

FieldSetter Int(int RigEstimatorOptions::*member) {
  return [member](const FieldReader& r, const YAML::Node& node, const std::string& field,
                  OnlineOptions* options) -> std::optional<Error> {
    auto v = r.Integer(node, field);
    if (!v) return Error{v.error()};
    options->estimator.*member = *v;
    return std::nullopt;
  };
}

// Durations are given in seconds in the config (the struct keeps nanoseconds).
FieldSetter Seconds(int64_t RigEstimatorOptions::*member) {
  return [member](const FieldReader& r, const YAML::Node& node, const std::string& field,
                  OnlineOptions* options) -> std::optional<Error> {
    auto v = r.Number(node, field);
    if (!v) return Error{v.error()};
    if (!(*v >= 0.0 && *v <= 86400.0)) return r.Fail(node, field, "must be in [0, 86400] s");
    options->estimator.*member = static_cast<int64_t>(std::llround(*v * 1e9));
    return std::nullopt;
  };
}

const std::map<std::string, FieldSetter>& EstimatorFields() {
  using O = RigEstimatorOptions;
  using M = ModelSelectionOptions;
  static const std::map<std::string, FieldSetter> fields = {
      {"keyframe_min_angle_deg", Double(&O::keyframe_min_angle_deg)},
      {"keyframe_min_travel_s", Double(&O::keyframe_min_travel_s)},
      {"keyframe_max_interval_s", Seconds(&O::keyframe_max_interval_ns)},
      {"keyframe_history", Int(&O::keyframe_history)},
      {"pair_target_angle_deg", Double(&O::pair_target_angle_deg)},
      {"pair_target_translation_fraction", Double(&O::pair_target_translation_fraction)},
      {"pair_max_span_s", Seconds(&O::pair_max_span_ns)},
      {"pair_min_angle_deg", Double(&O::pair_min_angle_deg)},
      {"gate_after_motions", Int(&O::gate_after_motions)},
      {"angle_gate_floor_deg", Double(&O::angle_gate_floor_deg)},
      {"gate_sigmas", Double(&O::gate_sigmas)},
      {"huber_sigmas", Double(&O::huber_sigmas)},
      {"scale_gate", Double(&O::scale_gate)},
      {"half_life_s", Double(&O::half_life_s)},
      {"short_half_life_s", Double(&O::short_half_life_s)},
      {"decalibration_sigmas", Double(&O::decalibration_sigmas)},
      {"decalibration_min_deg", Double(&O::decalibration_min_deg)},
      {"decalibration_min_translation", Double(&O::decalibration_min_translation)},
      {"decalibration_confirmations", Int(&O::decalibration_confirmations)},
      {"decalibration_confirm_s", Double(&O::decalibration_confirm_s)},
      {"max_open_segments", Int(&O::max_open_segments)},
      {"alpha_maxrot_deg", Double(&M::alpha_maxrot_deg)},
      {"alpha_maxrot_noise_deg", Double(&M::alpha_maxrot_noise_deg)},
      {"planar_axis_spread_deg", Double(&M::planar_axis_spread_deg)},
      {"min_tilt_snr", Double(&M::min_tilt_snr)},
      {"max_axis_std_ratio", Double(&M::max_axis_std_ratio)},
      {"general_axis_spread_deg", Double(&M::general_axis_spread_deg)},
      {"planar_hysteresis", Double(&O::planar_hysteresis)},
      {"nominal_sigma", Double(&O::nominal_sigma)},
      {"converged_min_motions", Int(&O::converged_min_motions)},
      {"converged_rot_std_deg", Double(&O::converged_rot_std_deg)},
      {"converged_pos_std_fraction", Double(&O::converged_pos_std_fraction)},
      {"converged_stable_keyframes", Int(&O::converged_stable_keyframes)},
      {"window_size", Int(&O::window_size)},
      {"history_sets", Int(&O::history_sets)},
      {"history_refine_period_s", Double(&O::history_refine_period_s)},
      {"sigma_block_s", Double(&O::sigma_block_s)},
      {"sigma_blocks", Int(&O::sigma_blocks)},
      {"sigma_min_blocks", Int(&O::sigma_min_blocks)},
      {"refine_period_s",
       [](const FieldReader& r, const YAML::Node& node, const std::string& field,
          OnlineOptions* options) -> std::optional<Error> {
         auto v = r.Number(node, field);
         if (!v) return Error{v.error()};
         options->refine_period_s = *v;
         return std::nullopt;
       }},
  };
  return fields;
}

std::optional<Error> ParseEstimator(const FieldReader& r, const YAML::Node& node,
                                    OnlineOptions* options) {
  std::set<std::string> known;
  for (const auto& [key, setter] : EstimatorFields()) known.insert(key);
  known.insert("time_offset");  // needs the cameras: ParseTimeOffsetSection
  if (node.IsMap() && node["keyframe_min_translation"]) {
    return r.Fail(node["keyframe_min_translation"], "estimator.keyframe_min_translation",
                  "removed: a length in the master's units depends on the unit its odometry "
                  "happened to set; use keyframe_min_travel_s (the master's median speed times "
                  "this many seconds)");
  }
  if (auto e = r.CheckKeys(node, "estimator.", known)) return e;
  for (auto it = node.begin(); it != node.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (key == "time_offset") continue;
    if (auto e = EstimatorFields().at(key)(r, it->second, "estimator." + key, options)) return e;
  }
  return std::nullopt;
}

Expected<int64_t> Milliseconds(const FieldReader& r, const YAML::Node& node,
                               const std::string& field) {
  auto v = r.Number(node, field);
  if (!v) return Error{v.error()};
  if (!(*v >= 0.0 && *v <= 3.6e6)) return r.Fail(node, field, "must be in [0, 3600000] ms");
  return static_cast<int64_t>(std::llround(*v * 1e6));
}

std::optional<Error> ParseSync(const FieldReader& r, const YAML::Node& node,
                               const std::vector<CameraConfig>& cameras, SyncOptions* sync) {
  if (auto e = r.CheckKeys(node, "sync.",
                           {"frame_rate_hz", "tolerance_ms", "max_wait_ms", "capacity",
                            "ready_capacity", "match_by_trigger_seq", "required"})) {
    return e;
  }
  if (const YAML::Node n = node["frame_rate_hz"]) {
    auto v = r.Number(n, "sync.frame_rate_hz");
    if (!v) return Error{v.error()};
    if (!(*v > 0.0 && *v <= 10000.0))
      return r.Fail(n, "sync.frame_rate_hz", "must be in (0, 10000]");
    sync->frame_period_ns = static_cast<int64_t>(std::llround(1e9 / *v));
  }
  if (const YAML::Node n = node["tolerance_ms"]) {
    auto v = Milliseconds(r, n, "sync.tolerance_ms");
    if (!v) return Error{v.error()};
    sync->tolerance_ns = *v;
  }
  if (const YAML::Node n = node["max_wait_ms"]) {
    auto v = Milliseconds(r, n, "sync.max_wait_ms");
    if (!v) return Error{v.error()};
    sync->max_wait_ns = *v;
  }
  if (const YAML::Node n = node["capacity"]) {
    auto v = r.Integer(n, "sync.capacity");
    if (!v) return Error{v.error()};
    sync->capacity = *v;
  }
  if (const YAML::Node n = node["ready_capacity"]) {
    auto v = r.Integer(n, "sync.ready_capacity");
    if (!v) return Error{v.error()};
    sync->ready_capacity = *v;
  }
  if (const YAML::Node n = node["match_by_trigger_seq"]) {
    auto v = r.Bool(n, "sync.match_by_trigger_seq");
    if (!v) return Error{v.error()};
    sync->match_by_trigger_seq = *v;
  }
  if (const YAML::Node n = node["required"]) {
    if (!n.IsSequence()) return r.Fail(n, "sync.required", "expected a list of camera names");
    sync->required.assign(cameras.size(), false);
    sync->required[0] = true;
    for (size_t i = 0; i < n.size(); ++i) {
      auto name = r.String(n[i], "sync.required[" + std::to_string(i) + "]");
      if (!name) return Error{name.error()};
      size_t k = 0;
      while (k < cameras.size() && cameras[k].name != *name) ++k;
      if (k == cameras.size()) {
        return r.Fail(n[i], "sync.required[" + std::to_string(i) + "]",
                      "'" + *name + "' is not a camera of the rig");
      }
      sync->required[k] = true;
    }
  }
  return std::nullopt;
}

std::optional<Error> ParseRate(const FieldReader& r, const YAML::Node& node,
                               const std::string& field, double* rate) {
  auto v = r.Number(node, field);
  if (!v) return Error{v.error()};
  if (!(*v > 0.0 && *v <= 1000.0)) return r.Fail(node, field, "must be in (0, 1000] Hz");
  *rate = *v;
  return std::nullopt;
}

// `rig:` and `cameras:`: fills config->name and config->cameras (the master first, then the
// others in file order); returns the cameras' YAML entries in that order.
Expected<std::vector<YAML::Node>> ParseCameras(const FieldReader& r, const YAML::Node& root,
                                               RigConfig* config) {
  const YAML::Node rig = root["rig"];
  if (!rig) return r.Fail(root, "rig", "missing (needs at least `master`)");
  if (auto e = r.CheckKeys(rig, "rig.", {"name", "master"})) return *e;
  if (const YAML::Node name = rig["name"]) {
    auto text = r.String(name, "rig.name");
    if (!text) return Error{text.error()};
    config->name = *text;
  }
  if (!rig["master"]) return r.Fail(rig, "rig.master", "missing");
  auto master = r.String(rig["master"], "rig.master");
  if (!master) return Error{master.error()};

  const YAML::Node cameras = root["cameras"];
  if (!cameras) return r.Fail(root, "cameras", "missing");
  if (!cameras.IsSequence() || cameras.size() < 2) {
    return r.Fail(cameras, "cameras", "expected a list of at least two cameras");
  }
  std::vector<CameraConfig> listed;
  std::set<std::string> names;
  for (size_t i = 0; i < cameras.size(); ++i) {
    auto camera = ParseCamera(r, cameras[i], config->path, i);
    if (!camera) return Error{camera.error()};
    if (!names.insert(camera->name).second) {
      return r.Fail(cameras[i]["name"], "cameras[" + std::to_string(i) + "].name",
                    "duplicate camera name '" + camera->name + "'");
    }
    listed.push_back(std::move(*camera));
  }
  size_t master_index = 0;
  while (master_index < listed.size() && listed[master_index].name != *master) ++master_index;
  if (master_index == listed.size()) {
    return r.Fail(rig["master"], "rig.master", "'" + *master + "' is not in cameras");
  }
  if (listed[master_index].nominal) {
    return r.Fail(cameras[master_index]["nominal"], *master + ".nominal",
                  "the master defines the rig frame; a nominal mounting is only for slaves");
  }
  for (size_t i = 0; i < listed.size(); ++i) {
    if (i != master_index && listed[i].metric) {
      return r.Fail(cameras[i]["metric"], listed[i].name + ".metric",
                    "only the master's odometry can be metric (its scale is fixed to 1); a "
                    "slave's scale is estimated");
    }
  }
  std::vector<YAML::Node> entries = {cameras[master_index]};
  config->cameras.push_back(listed[master_index]);
  for (size_t i = 0; i < listed.size(); ++i) {
    if (i == master_index) continue;
    entries.push_back(cameras[i]);
    config->cameras.push_back(std::move(listed[i]));
  }
  return entries;
}

// `estimator:` (with its time_offset) and `sync:` into config->online, with the cameras'
// metric master and nominal mountings; checks the whole.
std::optional<Error> ParseOnline(const FieldReader& r, const YAML::Node& root, RigConfig* config) {
  OnlineOptions& online = config->online;
  online.sync.num_cameras = static_cast<int>(config->cameras.size());
  if (const YAML::Node estimator = root["estimator"]) {
    if (auto e = ParseEstimator(r, estimator, &online)) return *e;
    if (const YAML::Node offset = estimator["time_offset"]) {
      std::vector<std::string> slaves;
      for (size_t i = 1; i < config->cameras.size(); ++i) {
        slaves.push_back(config->cameras[i].name);
      }
      auto parsed = ParseTimeOffsetSection(offset, slaves, config->master(), config->path);
      if (!parsed) return Error{parsed.error()};
      online.time_offset = *parsed;
    }
  }
  if (const YAML::Node sync = root["sync"]) {
    if (auto e = ParseSync(r, sync, config->cameras, &online.sync)) return *e;
  }
  online.estimator.master_metric = config->cameras.front().metric;
  online.estimator.nominal.assign(config->cameras.size() - 1, std::nullopt);
  for (size_t i = 1; i < config->cameras.size(); ++i) {
    online.estimator.nominal[i - 1] = config->cameras[i].nominal;
  }
  if (const Status checked = online.Check(); !checked.ok()) {
    return Error{config->path + ": estimator/sync options: " + checked.message()};
  }
  return std::nullopt;
}

// `publish:` (absent: the defaults).
std::optional<Error> ParsePublish(const FieldReader& r, const YAML::Node& publish,
                                  PublishOptions* options) {
  if (!publish) return std::nullopt;
  if (auto e = r.CheckKeys(publish, "publish.", {"extrinsics_rate_hz", "status_rate_hz"})) {
    return *e;
  }
  if (const YAML::Node n = publish["extrinsics_rate_hz"]) {
    if (auto e = ParseRate(r, n, "publish.extrinsics_rate_hz", &options->extrinsics_rate_hz)) {
      return *e;
    }
  }
  if (const YAML::Node n = publish["status_rate_hz"]) {
    if (auto e = ParseRate(r, n, "publish.status_rate_hz", &options->status_rate_hz)) return *e;
  }
  return std::nullopt;
}

// `state:` (absent: the defaults).
std::optional<Error> ParseState(const FieldReader& r, const YAML::Node& state,
                                StateOptions* options) {
  if (!state) return std::nullopt;
  if (auto e = r.CheckKeys(state, "state.", {"path", "save_interval_s"})) return *e;
  if (const YAML::Node n = state["path"]) {
    auto text = r.String(n, "state.path");
    if (!text) return Error{text.error()};
    options->path = *text;
  }
  if (const YAML::Node n = state["save_interval_s"]) {
    auto v = r.Number(n, "state.save_interval_s");
    if (!v) return Error{v.error()};
    if (!(*v > 0.0)) return r.Fail(n, "state.save_interval_s", "must be > 0");
    options->save_interval_s = *v;
  }
  return std::nullopt;
}

// The lines of the keys checked against this computer (RigConfig::key_lines).
void RecordKeyLines(const YAML::Node& root, const std::vector<YAML::Node>& entries,
                    RigConfig* config) {
  const auto record = [config](const YAML::Node& node, const std::string& key) {
    if (node && !node.Mark().is_null()) config->key_lines[key] = node.Mark().line + 1;
  };
  for (size_t i = 0; i < entries.size(); ++i) {
    record(entries[i]["device"], "cameras[" + std::to_string(i) + "].device");
  }
  if (const YAML::Node trigger = root["trigger"]; trigger && trigger.IsMap()) {
    record(trigger["port"], "trigger.port");
  }
}

}  // namespace

std::string RigConfig::Where(const std::string& key) const {
  const auto it = key_lines.find(key);
  return it == key_lines.end() ? path + ": " : path + ":" + std::to_string(it->second) + ": ";
}

std::vector<std::string> RigConfig::CameraNames() const {
  std::vector<std::string> names;
  names.reserve(cameras.size());
  for (const CameraConfig& camera : cameras) names.push_back(camera.name);
  return names;
}

Expected<RigConfig> LoadRigConfig(const std::string& path) {
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  return RigConfigFromYaml(*root, path);
}

Expected<RigConfig> RigConfigFromYaml(const YAML::Node& root, const std::string& path) {
  const FieldReader r(path);
  if (!root.IsMap()) return r.Fail(root, "(top level)", "expected a map with rig and cameras");
  if (auto e = r.CheckKeys(
          root, "",
          {"rig", "cameras", "estimator", "sync", "publish", "state", "source", "trigger"})) {
    return *e;
  }
  RigConfig config;
  config.path = path;
  auto entries = ParseCameras(r, root, &config);
  if (!entries) return Error{entries.error()};
  if (auto e = ParseOnline(r, root, &config)) return *e;
  if (auto e = ParsePublish(r, root["publish"], &config.publish)) return *e;
  if (auto e = ParseState(r, root["state"], &config.state)) return *e;
  // The hardware trigger, once the source is known (its stamps and exposures).
  auto source_type = ParseSourceSection(r, root, *entries, &config);
  if (!source_type) return Error{source_type.error()};
  if (auto e = ReadRigTrigger(r, root, *entries, *source_type, &config)) return *e;
  RecordKeyLines(root, *entries, &config);
  return config;
}

}  // namespace rigcal::io
