// SPDX-License-Identifier: Apache-2.0
#pragma once
// Reading YAML files with errors that point at the user's text: every message reads
// "<path>:<line>: <field>: <what is wrong>". Used by every YAML reader of tools/ (rig files,
// rig configs, camera and source sections).

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::io {


// Parses a YAML file; syntax errors name the path and line. A second document ("---") and a
// key that appears twice in a map are errors too ("<path>:<line>: <key>: duplicate key").
Expected<YAML::Node> LoadYaml(const std::string& path);

// Field access with errors of the form `<path>:<line>: <field>: <what>`.
class FieldReader {
 public:
  // `path` must outlive the reader.
  explicit FieldReader(const std::string& path) : path_(path) {}

  // "<path>:<line>: " of a node ("<path>: " when the node has no position).
  std::string At(const YAML::Node& node) const;
  Error Fail(const YAML::Node& node, const std::string& field, const std::string& what) const;

  // A finite number.
  Expected<double> Number(const YAML::Node& node, const std::string& field) const;
  Expected<int> Integer(const YAML::Node& node, const std::string& field) const;
  Expected<int64_t> Integer64(const YAML::Node& node, const std::string& field) const;
  Expected<bool> Bool(const YAML::Node& node, const std::string& field) const;
  Expected<std::string> String(const YAML::Node& node, const std::string& field) const;
  // A camera's name: it becomes part of LCM channel names and file names, so a non-empty
  // string of valid UTF-8 without control characters or '/', and not "." or "..".
  Expected<std::string> CameraName(const YAML::Node& node, const std::string& field) const;

  // A sequence of exactly `n` numbers at parent[key]; missing key is an error at the parent.
  Expected<std::vector<double>> Numbers(const YAML::Node& parent, const std::string& key,
                                        const std::string& field, size_t n) const;
  Expected<std::vector<double>> NumbersOf(const YAML::Node& node, const std::string& field,
                                          size_t n) const;
  // A rotation at parent[key] as [w, x, y, z] whose norm is 1 within 1e-3 (hand-typed digits),
  // normalised; a missing key is an error at the parent.
  Expected<Eigen::Quaterniond> UnitQuaternion(const YAML::Node& parent, const std::string& key,
                                              const std::string& field) const;
  // A sequence of any length >= min_n.
  Expected<std::vector<double>> NumberList(const YAML::Node& node, const std::string& field,
                                           size_t min_n = 0) const;

  // Error naming the first key of map `node` not in `known` ("<prefix><key>: unknown key;
  // expected one of ..."), or nullopt. A non-map node is an error too.
  std::optional<Error> CheckKeys(const YAML::Node& node, const std::string& prefix,
                                 const std::set<std::string>& known) const;

 private:
  const std::string& path_;
};

}  // namespace rigcal::io
