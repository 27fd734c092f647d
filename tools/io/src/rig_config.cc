#include "rigcal/io/rig_config.h"

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <set>

#include "rigcal/io/capture_source_yaml.h"
#include "rigcal/io/config_sections.h"
#include "rigcal/io/trigger_yaml.h"
#include "rigcal/io/yaml_fields.h"

namespace rigcal::tools {
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
  static const std::map<std::string, FieldSetter> fields = {
      {"keyframe_min_angle_deg", Double(&O::keyframe_min_angle_deg)},
      {"keyframe_min_translation", Double(&O::keyframe_min_translation)},
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
      {"alpha_maxrot_deg", Double(&O::alpha_maxrot_deg)},
      {"alpha_maxrot_noise_deg", Double(&O::alpha_maxrot_noise_deg)},
      {"planar_axis_spread_deg", Double(&O::planar_axis_spread_deg)},
      {"min_tilt_snr", Double(&O::min_tilt_snr)},
      {"max_axis_std_ratio", Double(&O::max_axis_std_ratio)},
      {"general_axis_spread_deg", Double(&O::general_axis_spread_deg)},
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

}  // namespace

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

  const YAML::Node rig = root["rig"];
  if (!rig) return r.Fail(root, "rig", "missing (needs at least `master`)");
  if (auto e = r.CheckKeys(rig, "rig.", {"name", "master"})) return *e;
  if (const YAML::Node name = rig["name"]) {
    auto text = r.String(name, "rig.name");
    if (!text) return Error{text.error()};
    config.name = *text;
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
    auto camera = ParseCamera(r, cameras[i], path, i);
    if (!camera) return Error{camera.error()};
    if (!names.insert(camera->name).second) {
      return r.Fail(cameras[i]["name"], "cameras[" + std::to_string(i) + "].name",
                    "duplicate camera name '" + camera->name + "'");
    }
    listed.push_back(std::move(*camera));
  }
  // The master first, then the others in file order.
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
  config.cameras.push_back(listed[master_index]);
  for (size_t i = 0; i < listed.size(); ++i) {
    if (i != master_index) config.cameras.push_back(std::move(listed[i]));
  }

  OnlineOptions& online = config.online;
  online.sync.num_cameras = static_cast<int>(config.cameras.size());
  if (const YAML::Node estimator = root["estimator"]) {
    if (auto e = ParseEstimator(r, estimator, &online)) return *e;
    if (const YAML::Node offset = estimator["time_offset"]) {
      std::vector<std::string> slaves;
      for (size_t i = 1; i < config.cameras.size(); ++i) slaves.push_back(config.cameras[i].name);
      auto parsed = ParseTimeOffsetSection(offset, slaves, config.master(), path);
      if (!parsed) return Error{parsed.error()};
      online.time_offset = *parsed;
    }
  }
  if (const YAML::Node sync = root["sync"]) {
    if (auto e = ParseSync(r, sync, config.cameras, &online.sync)) return *e;
  }
  online.estimator.master_metric = config.cameras.front().metric;
  online.estimator.nominal.assign(config.cameras.size() - 1, std::nullopt);
  for (size_t i = 1; i < config.cameras.size(); ++i) {
    online.estimator.nominal[i - 1] = config.cameras[i].nominal;
  }
  if (const Status checked = online.Check(); !checked.ok()) {
    return Error{path + ": estimator/sync options: " + checked.message()};
  }

  if (const YAML::Node publish = root["publish"]) {
    if (auto e = r.CheckKeys(publish, "publish.", {"extrinsics_rate_hz", "status_rate_hz"})) {
      return *e;
    }
    if (const YAML::Node n = publish["extrinsics_rate_hz"]) {
      if (auto e =
              ParseRate(r, n, "publish.extrinsics_rate_hz", &config.publish.extrinsics_rate_hz)) {
        return *e;
      }
    }
    if (const YAML::Node n = publish["status_rate_hz"]) {
      if (auto e = ParseRate(r, n, "publish.status_rate_hz", &config.publish.status_rate_hz)) {
        return *e;
      }
    }
  }
  if (const YAML::Node state = root["state"]) {
    if (auto e = r.CheckKeys(state, "state.", {"path", "save_interval_s"})) return *e;
    if (const YAML::Node n = state["path"]) {
      auto text = r.String(n, "state.path");
      if (!text) return Error{text.error()};
      config.state.path = *text;
    }
    if (const YAML::Node n = state["save_interval_s"]) {
      auto v = r.Number(n, "state.save_interval_s");
      if (!v) return Error{v.error()};
      if (!(*v > 0.0)) return r.Fail(n, "state.save_interval_s", "must be > 0");
      config.state.save_interval_s = *v;
    }
  }

  // The hardware trigger, once the source is known (its stamps and exposures).
  std::vector<YAML::Node> entries;
  for (size_t i = 0; i < config.cameras.size(); ++i) {
    entries.push_back(cameras[i == 0 ? master_index : (i <= master_index ? i - 1 : i)]);
  }
  std::string source_type;
  auto finish = [&]() -> Expected<RigConfig> {
    if (auto e = ReadRigTrigger(r, root, entries, source_type, &config)) return *e;
    return std::move(config);
  };
  if (const YAML::Node source = root["source"]) {
    if (!source.IsMap() || !source["type"]) return r.Fail(source, "source.type", "missing");
    auto type = r.String(source["type"], "source.type");
    if (!type) return Error{type.error()};
    source_type = *type;
    if (*type == "image_folders") {
      const std::filesystem::path base = std::filesystem::path(path).parent_path();
      drivers::ImageFolderOptions defaults;
      if (auto e = ParseImageFolderKeys(r, source, "source", true, base.string(), &defaults)) {
        return *e;
      }
      for (size_t i = 0; i < config.cameras.size(); ++i) {
        const CameraConfig& camera = config.cameras[i];
        const YAML::Node entry = cameras[i == 0 ? master_index : (i <= master_index ? i - 1 : i)];
        if (camera.device.empty()) {
          return r.Fail(entry, camera.name + ".device",
                        "missing: image_folders needs the camera's folder (e.g. mav0/cam0)");
        }
        if (!camera.spec) {
          return r.Fail(entry, camera.name,
                        "a camera of image_folders needs a model and intrinsics");
        }
        const std::filesystem::path folder(camera.device);
        config.image_folders.push_back(folder.is_absolute() ? folder.string()
                                                            : (base / folder).string());
        drivers::ImageFolderOptions options = defaults;
        if (const YAML::Node capture = entry["capture"]) {
          if (auto e = ParseImageFolderKeys(r, capture, camera.name + ".capture", false,
                                            base.string(), &options)) {
            return *e;
          }
        }
        config.image_folder_options.push_back(std::move(options));
      }
      return finish();
    }
    if (*type == "v4l2") {
      drivers::V4l2Options defaults;
      if (auto e = ParseV4l2Keys(r, source, "source", true, &defaults)) return *e;
      for (size_t i = 0; i < config.cameras.size(); ++i) {
        const CameraConfig& camera = config.cameras[i];
        const YAML::Node entry = cameras[i == 0 ? master_index : (i <= master_index ? i - 1 : i)];
        if (camera.device.empty()) {
          return r.Fail(entry, camera.name + ".device",
                        "missing: a v4l2 camera needs its device (/dev/videoN, "
                        "/dev/v4l/by-id/..., bus:<bus info> or card:<card name>)");
        }
        if (!camera.spec) {
          return r.Fail(entry, camera.name, "a v4l2 camera needs a model and intrinsics");
        }
        drivers::V4l2Options options = defaults;
        options.device = camera.device;
        options.width = camera.spec->width;
        options.height = camera.spec->height;
        if (const YAML::Node capture = entry["capture"]) {
          if (auto e = ParseV4l2Keys(r, capture, camera.name + ".capture", false, &options)) {
            return *e;
          }
        }
        config.v4l2_devices.push_back(std::move(options));
      }
      return finish();
    }
    if (*type == "libcamera") {
      drivers::LibcameraOptions defaults;
      if (auto e = ParseLibcameraKeys(r, source, "source", true, &defaults)) return *e;
      for (size_t i = 0; i < config.cameras.size(); ++i) {
        const CameraConfig& camera = config.cameras[i];
        const YAML::Node entry = cameras[i == 0 ? master_index : (i <= master_index ? i - 1 : i)];
        if (camera.device.empty()) {
          return r.Fail(entry, camera.name + ".device",
                        "missing: a libcamera camera needs its camera id or model (cam --list)");
        }
        if (!camera.spec) {
          return r.Fail(entry, camera.name, "a libcamera camera needs a model and intrinsics");
        }
        drivers::LibcameraOptions options = defaults;
        options.camera = camera.device;
        options.width = camera.spec->width;
        options.height = camera.spec->height;
        if (const YAML::Node capture = entry["capture"]) {
          if (auto e = ParseLibcameraKeys(r, capture, camera.name + ".capture", false, &options)) {
            return *e;
          }
        }
        config.libcamera_devices.push_back(std::move(options));
      }
      return finish();
    }
    for (size_t i = 0; i < cameras.size(); ++i) {
      if (cameras[i].IsMap() && cameras[i]["capture"]) {
        return r.Fail(cameras[i]["capture"], "cameras[" + std::to_string(i) + "].capture",
                      "only for a live source (source.type: v4l2 or libcamera)");
      }
    }
    if (*type != "simulated") {
      return r.Fail(source["type"], "source.type",
                    "'" + *type +
                        "' is not supported (supported: simulated, image_folders, v4l2, "
                        "libcamera)");
    }
    auto spec = ParseSimulatedSource(source, path);
    if (!spec) return Error{spec.error()};
    for (size_t i = 0; i < config.cameras.size(); ++i) {
      const CameraConfig& camera = config.cameras[i];
      const YAML::Node entry = cameras[i == 0 ? master_index : (i <= master_index ? i - 1 : i)];
      if (!camera.spec) {
        return r.Fail(entry, camera.name, "a simulated camera needs a model and intrinsics");
      }
      Similarity truth;  // the master is the rig frame
      if (i > 0) {
        if (!camera.truth) {
          return r.Fail(entry, camera.name + ".truth",
                        "missing: a simulated camera needs its true mounting");
        }
        truth = *camera.truth;
      }
      auto model = camera::MakeCameraModel(*camera.spec);
      if (!model) return r.Fail(entry, camera.name, model.error());
      spec->names.push_back(camera.name);
      spec->cameras.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
      Pose master_from_camera;
      master_from_camera.q = truth.q;
      master_from_camera.C = truth.C;
      spec->master_from_camera.push_back(master_from_camera);
    }
    if (const Status status = spec->Check(); !status.ok()) {
      return status.Prefixed(path + ": source");
    }
    config.simulated_source = std::move(*spec);
  }
  return finish();
}

}  // namespace rigcal::tools
