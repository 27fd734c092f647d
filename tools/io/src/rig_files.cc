// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/rig_files.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "rig_config_yaml.h"
#include "rigcal/base/format.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/rig_config.h"
#include "yaml_fields.h"

namespace rigcal::io {
namespace {

// Quaternions typed by hand with 4 decimals are off by up to ~1e-4.
constexpr double kRotationOrthonormalTolerance = 1e-6;
const std::set<std::string> kMetadataKeys = {"master", "pairs_selected"};

// Shortest round-trip text of a double; YAML spellings for non-finite values.
std::string YamlNumber(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  return ShortestText(v);
}

void EmitVector(YAML::Emitter& out, const double* v, int n) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < n; ++i) out << YamlNumber(v[i]);
  out << YAML::EndSeq;
}

void EmitRigEntry(YAML::Emitter& out, const Similarity& rig) {
  const std::array<double, 4> q = {rig.q.w(), rig.q.x(), rig.q.y(), rig.q.z()};
  out << YAML::Key << "q_wxyz" << YAML::Value;
  EmitVector(out, q.data(), 4);
  out << YAML::Key << "C" << YAML::Value;
  EmitVector(out, rig.C.data(), 3);
  out << YAML::Key << "scale" << YAML::Value << YamlNumber(rig.scale);
}

Expected<Similarity> ReadRigSlave(const FieldReader& r, const std::string& name,
                                  const YAML::Node& node) {
  if (!node.IsMap()) return r.Fail(node, name, "expected a map with q_wxyz, C and scale");
  // A hand-written rig entry holds only these keys; an entry of a result file (it has `usable`)
  // holds the statistics ResultToYaml writes as well.
  const bool rig_entry = !node["usable"];
  if (rig_entry) {
    if (auto e = r.CheckKeys(node, name + ".", {"q_wxyz", "C", "scale", "scales"})) return *e;
  }
  Similarity rig;
  auto q = r.UnitQuaternion(node, "q_wxyz", name + ".q_wxyz");
  if (!q) return Error{q.error()};
  rig.q = *q;
  auto c = r.Numbers(node, "C", name + ".C", 3);
  if (!c) return Error{c.error()};
  rig.C = Eigen::Vector3d((*c)[0], (*c)[1], (*c)[2]);
  const YAML::Node scale = node["scale"];
  if (!scale) return r.Fail(node, name + ".scale", "missing");
  auto s = r.Number(scale, name + ".scale");
  if (!s) return Error{s.error()};
  if (!(*s > 0.0)) return r.Fail(scale, name + ".scale", "must be > 0, got " + scale.Scalar());
  rig.scale = *s;

  if (const YAML::Node scales = node["scales"]) {
    if (!scales.IsSequence()) {
      return r.Fail(scales, name + ".scales", "expected a list of {segment, scale}");
    }
    std::map<int64_t, double> seen;  // segment -> scale
    for (size_t i = 0; i < scales.size(); ++i) {
      const std::string field = name + ".scales[" + std::to_string(i) + "]";
      const YAML::Node entry = scales[i];
      if (!entry.IsMap()) return r.Fail(entry, field, "expected {segment: id, scale: s}");
      if (rig_entry) {
        if (auto e = r.CheckKeys(entry, field + ".", {"segment", "scale"})) return *e;
      }
      if (!entry["segment"]) return r.Fail(entry, field + ".segment", "missing");
      if (!entry["scale"]) return r.Fail(entry, field + ".scale", "missing");
      auto id = r.Integer(entry["segment"], field + ".segment");
      if (!id) return Error{id.error()};
      auto value = r.Number(entry["scale"], field + ".scale");
      if (!value) return Error{value.error()};
      if (!(*value > 0.0)) return r.Fail(entry["scale"], field + ".scale", "must be > 0");
      // One scale per segment: a second entry (another value or the same) is an error.
      if (const auto [it, fresh] = seen.emplace(*id, *value); !fresh) {
        return r.Fail(entry["segment"], field + ".segment",
                      "segment " + std::to_string(*id) + " appears twice (scales " +
                          entry["scale"].Scalar() + " and " + YamlNumber(it->second) + ")");
      }
    }
  }
  return rig;
}

// ReadRigYaml of a loaded file.
Expected<std::map<std::string, Similarity>> RigFromYaml(const YAML::Node& root,
                                                        const std::string& path,
                                                        const std::string& expected_master) {
  const FieldReader r(path);
  if (!root.IsMap()) {
    return Error{r.At(root) + "expected a map from slave name to {q_wxyz, C, scale}"};
  }
  std::map<std::string, Similarity> rig;
  for (auto it = root.begin(); it != root.end(); ++it) {
    if (!it->first.IsScalar()) return Error{r.At(it->first) + "slave names must be scalars"};
    const std::string name = it->first.Scalar();
    if (name == "master" && it->second.IsScalar() && !expected_master.empty() &&
        it->second.Scalar() != expected_master) {
      return r.Fail(it->second, "master",
                    "the file is relative to master '" + it->second.Scalar() +
                        "', the rig's master is '" + expected_master + "'");
    }
    if (kMetadataKeys.count(name) && it->second.IsScalar()) continue;
    if (name == "provenance" && it->second.IsMap()) continue;  // provenance.h
    if (auto checked = r.CameraName(it->first, "slave name"); !checked) {
      return Error{checked.error()};
    }
    if (rig.count(name)) return r.Fail(it->first, name, "appears twice");
    auto slave = ReadRigSlave(r, name, it->second);
    if (!slave) return Error{slave.error()};
    rig.emplace(name, *slave);
  }
  if (rig.empty()) return Error{path + ": no slave entries"};
  return rig;
}

}  // namespace

Expected<std::map<std::string, Similarity>> ReadRigYaml(const std::string& path,
                                                        const std::string& expected_master) {
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  return RigFromYaml(*root, path, expected_master);
}

namespace {

// A rig YAML, or the mountings `field` (named `key`) of a rig config's cameras; the file is read
// and parsed once.
Expected<std::map<std::string, Similarity>> ReadMountings(
    const std::string& path, std::optional<Similarity> CameraConfig::*field, const char* key,
    const std::string& expected_master) {
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  const YAML::Node& loaded = *root;
  if (!loaded.IsMap() || !loaded["cameras"]) return RigFromYaml(loaded, path, expected_master);
  auto config = RigConfigFromYaml(loaded, path);
  if (!config) return Error{config.error()};
  std::map<std::string, Similarity> mountings;
  for (const CameraConfig& camera : config->cameras) {
    if (camera.*field) mountings.emplace(camera.name, *(camera.*field));
  }
  if (mountings.empty()) return Error{path + ": no camera has a `" + key + "` mounting"};
  return mountings;
}

}  // namespace

Expected<std::map<std::string, Similarity>> ReadNominalMountings(const std::string& path) {
  return ReadMountings(path, &CameraConfig::nominal, "nominal", "");
}

Expected<std::map<std::string, Similarity>> ReadTrueMountings(const std::string& path,
                                                              const std::string& expected_master) {
  return ReadMountings(path, &CameraConfig::truth, "truth", expected_master);
}

std::string RigToYaml(const std::map<std::string, Similarity>& rig) {
  return RigToYaml({rig.begin(), rig.end()}, "",
                   "rigcal rig: per slave its orientation q_wxyz and centre C in the master frame\n"
                   "(master units) and the scale mapping its odometry units to master units.");
}

std::string RigToYaml(const std::vector<std::pair<std::string, Similarity>>& slaves,
                      const std::string& master, const std::string& comment) {
  std::string text;
  std::istringstream comment_lines(comment);
  for (std::string line; std::getline(comment_lines, line);) text += "# " + line + "\n";
  YAML::Emitter out;
  out << YAML::BeginMap;
  if (!master.empty()) out << YAML::Key << "master" << YAML::Value << master;
  for (const auto& [name, similarity] : slaves) {
    out << YAML::Key << name << YAML::Value << YAML::BeginMap;
    EmitRigEntry(out, similarity);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return text + out.c_str() + "\n";
}

Status WriteRigYaml(const std::string& path, const std::map<std::string, Similarity>& rig) {
  return WriteFileAtomically(path, RigToYaml(rig));
}

std::string ResultToYaml(const RigCalibration& result) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "master" << YAML::Value << result.master;
  out << YAML::Key << "pairs_selected" << YAML::Value << result.pairs_selected;
  for (const SlaveCalibration& slave : result.slaves) {
    out << YAML::Key << slave.name << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "state" << YAML::Value << std::string(ToString(slave.state));
    out << YAML::Key << "usable" << YAML::Value << slave.usable();
    out << YAML::Key << "termination" << YAML::Value << ToString(slave.termination);
    out << YAML::Key << "message" << YAML::Value << slave.message;
    EmitRigEntry(out, slave.estimate);
    if (slave.scales.size() > 1) {
      out << YAML::Key << "scales" << YAML::Value << YAML::BeginSeq;
      for (const SegmentScale& s : slave.scales) {
        out << YAML::Flow << YAML::BeginMap << YAML::Key << "segment" << YAML::Value << s.segment
            << YAML::Key << "scale" << YAML::Value << YamlNumber(s.scale) << YAML::Key << "std"
            << YAML::Value << YamlNumber(s.std) << YAML::EndMap;
      }
      out << YAML::EndSeq;
    }
    out << YAML::Key << "std" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "rot_deg" << YAML::Value << YamlNumber(slave.rot_std_deg);
    out << YAML::Key << "pos" << YAML::Value;
    EmitVector(out, slave.pos_std.data(), 3);
    out << YAML::Key << "axis" << YAML::Value << YamlNumber(slave.axis_offset_std);
    if (slave.scales.size() == 1) {
      out << YAML::Key << "scale" << YAML::Value << YamlNumber(slave.scales.front().std);
    }
    out << YAML::EndMap;
    if (std::isfinite(slave.time_offset_s)) {
      out << YAML::Key << "time_offset_s" << YAML::Value << YamlNumber(slave.time_offset_s);
      out << YAML::Key << "time_offset_std_s" << YAML::Value << YamlNumber(slave.time_offset_std_s);
    }
    const MotionCounts& m = slave.motions;
    out << YAML::Key << "motions" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "total" << YAML::Value << m.total;
    out << YAML::Key << "used" << YAML::Value << m.used;
    out << YAML::Key << "rejected" << YAML::Value << m.rejected();
    out << YAML::Key << "small_rotation" << YAML::Value << m.small_rotation;
    out << YAML::Key << "angle_mismatch" << YAML::Value << m.angle_mismatch;
    out << YAML::Key << "residual_outlier" << YAML::Value << m.residual_outlier;
    out << YAML::EndMap;
    const GlitchCounts& g = slave.glitches;
    out << YAML::Key << "glitches" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "dropped" << YAML::Value << g.dropped();
    out << YAML::Key << "position_jump" << YAML::Value << g.position_jump;
    out << YAML::Key << "rotation_jump" << YAML::Value << g.rotation_jump;
    out << YAML::Key << "angle_mismatch" << YAML::Value << g.angle_mismatch;
    out << YAML::Key << "in_master" << YAML::Value << g.in_master;
    out << YAML::Key << "in_slave" << YAML::Value << g.in_slave;
    out << YAML::EndMap;
    out << YAML::Key << "models" << YAML::Value << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "motion" << YAML::Value << ToString(slave.motion_model);
    out << YAML::Key << "scale" << YAML::Value << ToString(slave.scale_model);
    out << YAML::EndMap;
    out << YAML::Key << "position_observable" << YAML::Value << slave.position_observable;
    out << YAML::Key << "unobservable" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const Eigen::Vector3d& d : slave.unobservable) EmitVector(out, d.data(), 3);
    out << YAML::EndSeq;
    out << YAML::Key << "unobservable_from_prior" << YAML::Value << slave.unobservable_from_prior;
    const Observability& o = slave.observability;
    out << YAML::Key << "observability" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "rotation_eigenvalues" << YAML::Value;
    EmitVector(out, o.rotation_eigenvalues.data(), 4);
    for (const auto& [key, value] :
         {std::pair<const char*, double>{"rotation_weak_std_deg", o.rotation_weak_std_deg},
          {"position_min_eigenvalue", o.position_min_eigenvalue},
          {"axis_spread_deg", o.axis_spread_deg},
          {"slave_axis_spread_deg", o.slave_axis_spread_deg},
          {"tilt_snr", o.tilt_snr},
          {"axis_std_ratio", o.axis_std_ratio},
          {"max_rotation_deg", o.max_rotation_deg}}) {
      out << YAML::Key << key << YAML::Value << YamlNumber(value);
    }
    out << YAML::Key << "planar" << YAML::Value << o.planar;
    out << YAML::Key << "mean_axis" << YAML::Value;
    EmitVector(out, o.planar_axis.data(), 3);
    out << YAML::EndMap;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  return std::string(
             "# rigcal solve result. Per slave: orientation q_wxyz and centre C in the master\n"
             "# frame (master odometry units), scale = slave odometry unit -> master unit.\n"
             "# Use an entry only when usable is true; termination and message say why not.\n") +
         out.c_str() + "\n";
}

Status WriteResultYaml(const std::string& path, const RigCalibration& result) {
  return WriteFileAtomically(path, ResultToYaml(result));
}

Expected<std::vector<CamchainCamera>> ReadCamchain(const std::string& path) {
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  const FieldReader r(path);
  if (!root->IsMap() || !(*root)["cam0"]) {
    return Error{r.At(*root) + "expected a map with cam0, cam1, ..."};
  }
  std::vector<CamchainCamera> cameras;
  for (int n = 0;; ++n) {
    const std::string key = "cam" + std::to_string(n);
    const YAML::Node cam = (*root)[key];
    if (!cam) break;
    if (!cam.IsMap()) return r.Fail(cam, key, "expected a map");
    CamchainCamera camera;
    if (const YAML::Node name = cam["rigcal_name"]; name && name.IsScalar()) {
      camera.name = name.Scalar();
    }
    if (n > 0) {
      const std::string field = key + ".T_cn_cnm1";
      const YAML::Node t = cam["T_cn_cnm1"];
      if (!t) return r.Fail(cam, field, "missing");
      if (!t.IsSequence() || t.size() != 4) return r.Fail(t, field, "expected 4 rows");
      for (int row = 0; row < 4; ++row) {
        auto values = r.NumbersOf(t[row], field + "[" + std::to_string(row) + "]", 4);
        if (!values) return Error{values.error()};
        for (int col = 0; col < 4; ++col) camera.cn_from_cnm1(row, col) = (*values)[col];
      }
      const Eigen::RowVector4d last = camera.cn_from_cnm1.row(3);
      if ((last - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12) {
        return r.Fail(t, field, "last row must be [0, 0, 0, 1]");
      }
      const Eigen::Matrix3d rot = camera.cn_from_cnm1.topLeftCorner<3, 3>();
      if ((rot * rot.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() >
              kRotationOrthonormalTolerance ||
          rot.determinant() < 0.0) {
        return r.Fail(t, field, "rotation block is not a rotation matrix");
      }
    }
    cameras.push_back(camera);
  }
  return cameras;
}

}  // namespace rigcal::io
