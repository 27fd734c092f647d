// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/result_file.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <set>

#include "rigcal/base/format.h"
#include "rigcal/io/text_file.h"
#include "yaml_fields.h"

namespace rigcal::io {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Quaternions are written in shortest round-trip form; hand-edited files may carry 4 decimals.
const std::set<std::string> kYamlMetadataKeys = {"master", "pairs_selected"};

// parent[key], or an error naming `field` at the parent when it is missing.
Expected<YAML::Node> Child(const FieldReader& r, const YAML::Node& parent, const char* key,
                           const std::string& field) {
  if (!parent.IsMap()) return r.Fail(parent, field, "expected a map around it");
  YAML::Node child = parent[key];
  if (!child) return r.Fail(parent, field, "missing");
  return child;
}

// A number that may be unknown: .nan, null or ~ (the writers' spellings of an unknown σ).
Expected<double> MaybeNumber(const FieldReader& r, const YAML::Node& node,
                             const std::string& field) {
  if (!node || node.IsNull()) return kNaN;
  if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    if (text == ".nan" || text == ".NaN" || text == ".NAN" || text == "nan") return kNaN;
    if (text == ".inf" || text == "+.inf") return std::numeric_limits<double>::infinity();
    if (text == "-.inf") return -std::numeric_limits<double>::infinity();
  }
  return r.Number(node, field);
}

template <typename Enum, size_t N>
Expected<Enum> NamedValue(const FieldReader& r, const YAML::Node& parent, const char* key,
                          const std::string& field, const Enum (&values)[N]) {
  auto child = Child(r, parent, key, field);
  if (!child) return Error{child.error()};
  const YAML::Node node = *child;
  auto text = r.String(node, field);
  if (!text) return Error{text.error()};
  std::string known;
  for (const Enum value : values) {
    if (std::string(ToString(value)) == *text) return value;
    known += (known.empty() ? "" : ", ") + std::string(ToString(value));
  }
  return r.Fail(node, field, "unknown value '" + *text + "'; expected one of " + known);
}

constexpr SlaveState kStates[] = {SlaveState::kInitialising, SlaveState::kUsable,
                                  SlaveState::kConverged, SlaveState::kDecalibrated};
constexpr Termination kTerminations[] = {Termination::kSolved, Termination::kNoConvergence,
                                         Termination::kInsufficientMotion, Termination::kDegenerate,
                                         Termination::kInvalidInput};
constexpr MotionModel kMotionModels[] = {MotionModel::kGeneral, MotionModel::kTranslational,
                                         MotionModel::kPlanar};
constexpr ScaleModel kScaleModels[] = {ScaleModel::kFixed, ScaleModel::kSegments,
                                       ScaleModel::kPartitions};

Status ReadEstimate(const FieldReader& r, const YAML::Node& node, const std::string& name,
                    SlaveCalibration* slave) {
  auto q = r.UnitQuaternion(node, "q_wxyz", name + ".q_wxyz");
  if (!q) return Error{q.error()};
  slave->estimate.q = *q;
  auto c = r.Numbers(node, "C", name + ".C", 3);
  if (!c) return Error{c.error()};
  slave->estimate.C = Eigen::Vector3d((*c)[0], (*c)[1], (*c)[2]);
  if (const YAML::Node scales = node["scales"]) {
    if (!scales.IsSequence() || scales.size() == 0) {
      return r.Fail(scales, name + ".scales", "expected a list of {segment, scale, std}");
    }
    for (size_t i = 0; i < scales.size(); ++i) {
      const std::string field = name + ".scales[" + std::to_string(i) + "]";
      SegmentScale segment;
      auto id_node = Child(r, scales[i], "segment", field + ".segment");
      if (!id_node) return Error{id_node.error()};
      auto id = r.Integer(*id_node, field + ".segment");
      if (!id) return Error{id.error()};
      auto value_node = Child(r, scales[i], "scale", field + ".scale");
      if (!value_node) return Error{value_node.error()};
      auto value = r.Number(*value_node, field + ".scale");
      if (!value) return Error{value.error()};
      auto std = MaybeNumber(r, scales[i]["std"], field + ".std");
      if (!std) return Error{std.error()};
      segment.segment = *id;
      segment.scale = *value;
      segment.std = *std;
      slave->scales.push_back(segment);
    }
    slave->estimate.scale = slave->scales.front().scale;
  } else {
    if (!node["scale"]) return r.Fail(node, name + ".scale", "missing (nor `scales`)");
    auto scale = r.Number(node["scale"], name + ".scale");
    if (!scale) return Error{scale.error()};
    slave->estimate.scale = *scale;
    SegmentScale segment;
    segment.scale = *scale;
    const YAML::Node std_node = node["std"];
    auto std = MaybeNumber(r, std_node && std_node.IsMap() ? std_node["scale"] : YAML::Node(),
                           name + ".std.scale");
    if (!std) return Error{std.error()};
    segment.std = *std;
    slave->scales.push_back(segment);
  }
  return {};
}

Status ReadUncertainty(const FieldReader& r, const YAML::Node& node, const std::string& name,
                       SlaveCalibration* slave) {
  const YAML::Node std = node["std"];
  if (!std || !std.IsMap()) return r.Fail(node, name + ".std", "missing {rot_deg, pos, axis}");
  auto rot = MaybeNumber(r, std["rot_deg"], name + ".std.rot_deg");
  if (!rot) return Error{rot.error()};
  slave->rot_std_deg = *rot;
  auto pos_node = Child(r, std, "pos", name + ".std.pos");
  if (!pos_node) return Error{pos_node.error()};
  const YAML::Node pos = *pos_node;
  if (!pos.IsSequence() || pos.size() != 3) {
    return r.Fail(pos, name + ".std.pos", "expected 3 numbers (or null/.nan)");
  }
  for (int i = 0; i < 3; ++i) {
    auto v = MaybeNumber(r, pos[i], name + ".std.pos[" + std::to_string(i) + "]");
    if (!v) return Error{v.error()};
    slave->pos_std[i] = *v;
  }
  auto axis = MaybeNumber(r, std["axis"], name + ".std.axis");
  if (!axis) return Error{axis.error()};
  slave->axis_offset_std = *axis;
  auto offset = MaybeNumber(r, node["time_offset_s"], name + ".time_offset_s");
  if (!offset) return Error{offset.error()};
  slave->time_offset_s = *offset;
  auto offset_std = MaybeNumber(r, node["time_offset_std_s"], name + ".time_offset_std_s");
  if (!offset_std) return Error{offset_std.error()};
  slave->time_offset_std_s = *offset_std;
  return {};
}

// One slave entry; the YAML and JSON schemas differ only in where the motion counts are.
Expected<SlaveCalibration> ReadResultSlave(const FieldReader& r, const YAML::Node& node,
                                           const std::string& name, bool json) {
  if (!node.IsMap()) return r.Fail(node, name, "expected a map (a slave's result)");
  SlaveCalibration slave;
  slave.name = name;
  if (Status s = ReadEstimate(r, node, name, &slave); !s.ok()) return s;
  if (Status s = ReadUncertainty(r, node, name, &slave); !s.ok()) return s;
  auto state = NamedValue(r, node, "state", name + ".state", kStates);
  if (!state) return Error{state.error()};
  slave.state = *state;
  auto termination = NamedValue(r, node, "termination", name + ".termination", kTerminations);
  if (!termination) return Error{termination.error()};
  slave.termination = *termination;
  if (node["message"]) {
    auto message = r.String(node["message"], name + ".message");
    if (!message) return Error{message.error()};
    slave.message = *message;
  }
  if (const YAML::Node models = node["models"]) {
    auto motion = NamedValue(r, models, "motion", name + ".models.motion", kMotionModels);
    if (!motion) return Error{motion.error()};
    auto scale = NamedValue(r, models, "scale", name + ".models.scale", kScaleModels);
    if (!scale) return Error{scale.error()};
    slave.motion_model = *motion;
    slave.scale_model = *scale;
  }
  if (json) {
    auto used_node = Child(r, node, "motions_used", name + ".motions_used");
    if (!used_node) return Error{used_node.error()};
    auto used = r.Integer(*used_node, name + ".motions_used");
    if (!used) return Error{used.error()};
    auto rejected_node = Child(r, node, "motions_rejected", name + ".motions_rejected");
    if (!rejected_node) return Error{rejected_node.error()};
    auto rejected = r.Integer(*rejected_node, name + ".motions_rejected");
    if (!rejected) return Error{rejected.error()};
    slave.motions.used = *used;
    slave.motions.residual_outlier = *rejected;
    slave.motions.total = *used + *rejected;
  } else {
    const YAML::Node motions = node["motions"];
    if (!motions || !motions.IsMap()) return r.Fail(node, name + ".motions", "missing");
    int* counts[] = {&slave.motions.total, &slave.motions.used, &slave.motions.small_rotation,
                     &slave.motions.angle_mismatch, &slave.motions.residual_outlier};
    const char* keys[] = {"total", "used", "small_rotation", "angle_mismatch", "residual_outlier"};
    for (int i = 0; i < 5; ++i) {
      auto count = Child(r, motions, keys[i], name + ".motions." + keys[i]);
      if (!count) return Error{count.error()};
      auto n = r.Integer(*count, name + ".motions." + keys[i]);
      if (!n) return Error{n.error()};
      *counts[i] = *n;
    }
  }
  slave.position_observable = slave.motion_model != MotionModel::kTranslational;
  return slave;
}

}  // namespace

Expected<RigCalibration> ReadResultFile(const std::string& path) {
  auto text = ReadWholeFile(path);
  if (!text) return Error{text.error()};
  const size_t first = text->find_first_not_of(" \t\r\n");
  const bool json = first != std::string::npos && (*text)[first] == '{';
  auto root = LoadYaml(path);  // JSON is YAML: one reader, errors with lines for both
  if (!root) return Error{root.error()};
  const FieldReader r(path);
  if (!root->IsMap()) return Error{r.At(*root) + "expected a result (a map)"};
  RigCalibration result;
  if ((*root)["master"]) {
    auto master = r.String((*root)["master"], "master");
    if (!master) return Error{master.error()};
    result.master = *master;
  }
  if (json) {
    const YAML::Node slaves = (*root)["slaves"];
    if (!slaves || !slaves.IsSequence()) {
      return r.Fail(*root, "slaves", "missing (a list of slave results)");
    }
    for (size_t i = 0; i < slaves.size(); ++i) {
      auto name_node = Child(r, slaves[i], "name", "slaves[" + std::to_string(i) + "].name");
      if (!name_node) return Error{name_node.error()};
      auto name = r.CameraName(*name_node, "slaves[" + std::to_string(i) + "].name");
      if (!name) return Error{name.error()};
      auto slave = ReadResultSlave(r, slaves[i], *name, true);
      if (!slave) return Error{slave.error()};
      result.slaves.push_back(std::move(*slave));
    }
  } else {
    if (const YAML::Node pairs = (*root)["pairs_selected"]) {
      auto n = r.Integer(pairs, "pairs_selected");
      if (!n) return Error{n.error()};
      result.pairs_selected = *n;
    }
    for (auto it = root->begin(); it != root->end(); ++it) {
      const std::string key = it->first.Scalar();
      if (kYamlMetadataKeys.count(key) && it->second.IsScalar()) continue;
      if (key == "provenance" && it->second.IsMap()) continue;  // provenance.h
      auto slave = ReadResultSlave(r, it->second, key, false);
      if (!slave) return Error{slave.error()};
      result.slaves.push_back(std::move(*slave));
    }
  }
  if (result.slaves.empty()) return Error{path + ": no slave results"};
  return result;
}

Expected<std::string> ReadResultDistanceUnit(const std::string& path) {
  auto root = LoadYaml(path);  // JSON is YAML (ReadResultFile)
  if (!root) return Error{root.error()};
  if (!root->IsMap()) return std::string();
  const YAML::Node provenance = (*root)["provenance"];
  if (!provenance || !provenance.IsMap()) return std::string();
  const YAML::Node units = provenance["units"];
  if (!units || !units.IsMap() || !units["C"] || !units["C"].IsScalar()) return std::string();
  return units["C"].Scalar();
}

}  // namespace rigcal::io
