// SPDX-License-Identifier: Apache-2.0
// Camera intrinsics from YAML: one `cameras:` entry of a rig config (docs/config.md), and the
// cameras of a Kalibr camchain file. Both fill camera::CameraSpec and check it, so that every error
// points at the line of the offending key.
#include <algorithm>
#include <array>
#include <cctype>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "config_sections.h"
#include "rigcal/io/camera_files.h"
#include "yaml_fields.h"

namespace rigcal::io {
namespace {

using camera::CameraSpec;

// Keys of a camera entry: read here, or owned by the rig config parser (nominal, truth, device,
// metric).
const std::set<std::string> kCameraKeys = {
    "name",
    "model",
    "resolution",
    "intrinsics",
    "distortion",
    "poly",
    "inverse_poly",
    "center",
    "affine",
    "max_field_angle_deg",
    "rolling_shutter_ms",
    "nominal",
    "truth",
    "device",
    "capture",
    "trigger",
    "metric",
};
// Keys that only some models use.
const std::set<std::string> kProjectiveKeys = {"intrinsics", "distortion"};  // pinhole, fisheye
const std::set<std::string> kScaramuzzaKeys = {"poly", "inverse_poly", "center", "affine"};

// `parent[key]` as [width, height]; a missing key is reported at `missing_at`.
Expected<std::array<int, 2>> ReadResolution(const FieldReader& r, const YAML::Node& parent,
                                            const YAML::Node& missing_at, const std::string& key,
                                            const std::string& field) {
  const YAML::Node node = parent[key];
  if (!node) return r.Fail(missing_at, field, "missing (expected [width, height])");
  if (!node.IsSequence() || node.size() != 2) {
    return r.Fail(node, field, "expected [width, height]");
  }
  std::array<int, 2> size{};
  for (size_t i = 0; i < 2; ++i) {
    auto v = r.Integer(node[i], field + "[" + std::to_string(i) + "]");
    if (!v) return Error{v.error()};
    if (*v <= 0) return r.Fail(node[i], field, "width and height must be > 0");
    size[i] = *v;
  }
  return size;
}

// The key node of `key` in map `map` (its line is the line of "key:"), or an invalid node.
YAML::Node KeyNode(const YAML::Node& map, const std::string& key) {
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (it->first.Scalar() == key) return it->first;
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

// A list of numbers whose length is one of `sizes`; `expected` describes them for the message.
Expected<std::vector<double>> ReadList(const FieldReader& r, const YAML::Node& node,
                                       const std::string& field, const std::vector<size_t>& sizes,
                                       const std::string& expected) {
  if (!node.IsSequence()) return r.Fail(node, field, "expected a list " + expected);
  if (!sizes.empty() && std::find(sizes.begin(), sizes.end(), node.size()) == sizes.end()) {
    return r.Fail(node, field,
                  "expected " + expected + ", got " + std::to_string(node.size()) + " values");
  }
  return r.NumberList(node, field);
}

// The spec's own check, reported at the line of the key it names (`key_of` renames spec fields
// to the keys of the file; a field without a key in the file is reported at `missing_at`).
std::optional<Error> CheckSpec(const FieldReader& r, const CameraSpec& spec,
                               const YAML::Node& camera, const YAML::Node& missing_at,
                               const std::string& prefix,
                               const std::map<std::string, std::string>& key_of = {}) {
  const Status status = spec.Check();
  if (status.ok()) return std::nullopt;
  // The message is "<field>: <what>".
  const std::string& message = status.message();
  const size_t colon = message.find(": ");
  const std::string field = message.substr(0, colon);
  const std::string what = colon == std::string::npos ? message : message.substr(colon + 2);
  const auto renamed = key_of.find(field);
  const std::string key = renamed == key_of.end() ? field : renamed->second;
  const YAML::Node node = KeyNode(camera, key);
  return r.Fail(node.IsDefined() ? node : missing_at, prefix + key, what);
}

}  // namespace

Expected<CameraSpec> ParseCameraSection(const YAML::Node& camera, const std::string& path) {
  const FieldReader r(path);
  if (!camera.IsMap()) return r.Fail(camera, "cameras[]", "expected a map with name and model");
  if (!camera["name"]) return r.Fail(camera, "name", "missing");
  auto name = r.CameraName(camera["name"], "name");
  if (!name) return Error{name.error()};
  const std::string prefix = *name + ".";
  if (auto e = r.CheckKeys(camera, prefix, kCameraKeys)) return *e;

  CameraSpec spec;
  spec.name = *name;
  const YAML::Node model_node = camera["model"];
  if (!model_node)
    return r.Fail(camera, prefix + "model", "missing (pinhole, fisheye or scaramuzza)");
  auto model_name = r.String(model_node, prefix + "model");
  if (!model_name) return Error{model_name.error()};
  const std::optional<CameraSpec::Model> model = camera::ModelFromName(*model_name);
  if (!model) {
    return r.Fail(model_node, prefix + "model",
                  "'" + *model_name + "' is not a camera model (pinhole, fisheye or scaramuzza)");
  }
  spec.model = *model;
  const bool scaramuzza = spec.model == CameraSpec::Model::kScaramuzza;
  for (auto it = camera.begin(); it != camera.end(); ++it) {
    const std::string key = it->first.Scalar();
    if ((scaramuzza && kProjectiveKeys.count(key)) || (!scaramuzza && kScaramuzzaKeys.count(key))) {
      return r.Fail(it->first, prefix + key, "not used by model " + *model_name);
    }
  }

  auto resolution = ReadResolution(r, camera, camera, "resolution", prefix + "resolution");
  if (!resolution) return Error{resolution.error()};
  spec.width = (*resolution)[0];
  spec.height = (*resolution)[1];

  if (!scaramuzza) {
    auto intrinsics = r.Numbers(camera, "intrinsics", prefix + "intrinsics", 4);
    if (!intrinsics) return Error{intrinsics.error()};
    std::copy(intrinsics->begin(), intrinsics->end(), spec.intrinsics.begin());
    if (const YAML::Node node = camera["distortion"]) {
      const bool pinhole = spec.model == CameraSpec::Model::kPinhole;
      auto distortion =
          ReadList(r, node, prefix + "distortion",
                   pinhole ? std::vector<size_t>{4, 5} : std::vector<size_t>{4},
                   pinhole ? "[k1, k2, p1, p2] or [k1, k2, p1, p2, k3]" : "[k1, k2, k3, k4]");
      if (!distortion) return Error{distortion.error()};
      spec.distortion = std::move(*distortion);
    }
  } else {
    const YAML::Node poly = camera["poly"];
    if (!poly) return r.Fail(camera, prefix + "poly", "missing (a0, a1, ... as OCamCalib)");
    auto coefficients = ReadList(r, poly, prefix + "poly", {}, "of numbers a0, a1, ...");
    if (!coefficients) return Error{coefficients.error()};
    spec.poly = std::move(*coefficients);
    if (const YAML::Node node = camera["inverse_poly"]) {
      auto inverse = ReadList(r, node, prefix + "inverse_poly", {}, "of numbers");
      if (!inverse) return Error{inverse.error()};
      spec.inverse_poly = std::move(*inverse);
    }
    auto center = r.Numbers(camera, "center", prefix + "center", 2);
    if (!center) return Error{center.error()};
    spec.center = {(*center)[0], (*center)[1]};
    if (const YAML::Node node = camera["affine"]) {
      auto affine = r.NumbersOf(node, prefix + "affine", 3);
      if (!affine) return Error{affine.error()};
      spec.affine = {(*affine)[0], (*affine)[1], (*affine)[2]};
    }
  }
  if (const YAML::Node node = camera["max_field_angle_deg"]) {
    auto angle = r.Number(node, prefix + "max_field_angle_deg");
    if (!angle) return Error{angle.error()};
    spec.max_field_angle_deg = *angle;
  }
  if (const YAML::Node node = camera["rolling_shutter_ms"]) {
    auto readout = r.Number(node, prefix + "rolling_shutter_ms");
    if (!readout) return Error{readout.error()};
    spec.rolling_shutter_s = *readout * 1e-3;
  }
  if (auto e = CheckSpec(r, spec, camera, camera, prefix)) return *e;
  return spec;
}

namespace {

// The Kalibr model pair (camera_model, distortion_model) as rigcal's model, with the number of
// distortion coefficients it takes.
Expected<size_t> ReadKalibrModel(const FieldReader& r, const YAML::Node& camera,
                                 const YAML::Node& key_node, const std::string& prefix,
                                 CameraSpec* spec) {
  const auto missing = [&](const std::string& key) {
    return r.Fail(key_node, prefix + key, "missing");
  };
  const YAML::Node model_node = camera["camera_model"];
  if (!model_node) return missing("camera_model");
  auto model = r.String(model_node, prefix + "camera_model");
  if (!model) return Error{model.error()};
  const YAML::Node distortion_node = camera["distortion_model"];
  if (!distortion_node) return missing("distortion_model");
  auto distortion_model = r.String(distortion_node, prefix + "distortion_model");
  if (!distortion_model) return Error{distortion_model.error()};
  const std::string supported =
      "rigcal reads Kalibr camera_model pinhole with distortion_model radtan (as pinhole), "
      "equidistant (as fisheye) or none";
  if (*model != "pinhole") {
    return r.Fail(model_node, prefix + "camera_model",
                  "camera " + spec->name + ": Kalibr model '" + *model + "' (with " +
                      *distortion_model + ") is not supported; " + supported);
  }
  if (*distortion_model == "radtan") {
    spec->model = CameraSpec::Model::kPinhole;
    return size_t{4};
  }
  if (*distortion_model == "equidistant") {
    spec->model = CameraSpec::Model::kFisheye;
    return size_t{4};
  }
  if (*distortion_model == "none") {
    spec->model = CameraSpec::Model::kPinhole;
    return size_t{0};
  }
  return r.Fail(distortion_node, prefix + "distortion_model",
                "camera " + spec->name + ": Kalibr model pinhole-" + *distortion_model +
                    " is not supported; " + supported);
}

// resolution, intrinsics and distortion_coeffs (`coefficients` of them) of one camera.
std::optional<Error> ReadKalibrNumbers(const FieldReader& r, const YAML::Node& camera,
                                       const YAML::Node& key_node, const std::string& prefix,
                                       size_t coefficients, CameraSpec* spec) {
  const auto missing = [&](const std::string& key, const std::string& expected) {
    return r.Fail(key_node, prefix + key, "missing" + expected);
  };
  auto resolution = ReadResolution(r, camera, key_node, "resolution", prefix + "resolution");
  if (!resolution) return Error{resolution.error()};
  spec->width = (*resolution)[0];
  spec->height = (*resolution)[1];
  if (!camera["intrinsics"]) return missing("intrinsics", " (expected [fu, fv, pu, pv])");
  auto intrinsics = r.NumbersOf(camera["intrinsics"], prefix + "intrinsics", 4);
  if (!intrinsics) return Error{intrinsics.error()};
  std::copy(intrinsics->begin(), intrinsics->end(), spec->intrinsics.begin());
  const YAML::Node coeffs = camera["distortion_coeffs"];
  if (coefficients > 0) {
    if (!coeffs) return missing("distortion_coeffs", " (expected 4 numbers)");
    auto values = r.NumbersOf(coeffs, prefix + "distortion_coeffs", coefficients);
    if (!values) return Error{values.error()};
    spec->distortion = std::move(*values);
  } else if (coeffs && !(coeffs.IsSequence() && coeffs.size() == 0)) {
    return r.Fail(coeffs, prefix + "distortion_coeffs",
                  "expected [] or nothing with distortion_model none");
  }
  return std::nullopt;
}

// One camera `camN` of the camchain (its key node for errors about it as a whole); `names`
// collects the names taken so far.
Expected<CameraSpec> ReadKalibrCamera(const FieldReader& r, const YAML::Node& key_node,
                                      const YAML::Node& camera, const std::string& cam,
                                      std::set<std::string>* names) {
  const std::string prefix = cam + ".";
  if (!camera.IsMap()) return r.Fail(key_node, cam, "expected a map");
  CameraSpec spec;
  spec.name = cam;
  if (const YAML::Node node = camera["rigcal_name"]) {
    auto name = r.CameraName(node, prefix + "rigcal_name");
    if (!name) return Error{name.error()};
    spec.name = *name;
  }
  if (!names->insert(spec.name).second) {
    return r.Fail(camera["rigcal_name"] ? KeyNode(camera, "rigcal_name") : key_node,
                  prefix + "rigcal_name", "duplicate camera name '" + spec.name + "'");
  }
  auto coefficients = ReadKalibrModel(r, camera, key_node, prefix, &spec);
  if (!coefficients) return Error{coefficients.error()};
  if (auto e = ReadKalibrNumbers(r, camera, key_node, prefix, *coefficients, &spec)) return *e;
  if (auto e =
          CheckSpec(r, spec, camera, key_node, prefix, {{"distortion", "distortion_coeffs"}})) {
    return *e;
  }
  return spec;
}

}  // namespace

Expected<std::vector<CameraSpec>> ReadKalibrIntrinsics(const std::string& path) {
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  const FieldReader r(path);
  if (!root->IsMap() || root->size() == 0) {
    return r.Fail(*root, "(top level)", "expected a Kalibr camchain: a map of cam0, cam1, ...");
  }
  // Top-level keys are cam0 .. camN-1 (any order in the file). Keep the key nodes: errors about
  // a camera as a whole, or a key missing from it, are reported at the line of "camN:".
  std::map<int, std::pair<YAML::Node, YAML::Node>> cameras;
  for (auto it = root->begin(); it != root->end(); ++it) {
    const std::string key = it->first.Scalar();
    const bool is_cam = key.size() > 3 && key.size() < 8 && key.compare(0, 3, "cam") == 0 &&
                        std::all_of(key.begin() + 3, key.end(),
                                    [](unsigned char ch) { return std::isdigit(ch) != 0; });
    if (!is_cam) {
      return r.Fail(it->first, key, "unknown key; a Kalibr camchain has cam0, cam1, ...");
    }
    cameras[std::stoi(key.substr(3))] = {it->first, it->second};
  }
  std::vector<CameraSpec> specs;
  std::set<std::string> names;
  for (const auto& [index, entry] : cameras) {
    const std::string cam = "cam" + std::to_string(index);
    if (index != static_cast<int>(specs.size())) {
      return r.Fail(entry.first, cam,
                    "cameras must be numbered cam0, cam1, ... without gaps (cam" +
                        std::to_string(specs.size()) + " is missing)");
    }
    auto spec = ReadKalibrCamera(r, entry.first, entry.second, cam, &names);
    if (!spec) return Error{spec.error()};
    specs.push_back(std::move(*spec));
  }
  return specs;
}

}  // namespace rigcal::io
