// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/provenance.h"

#include <yaml-cpp/yaml.h>

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>

namespace rigcal::io {

InputFile DescribeInput(const std::string& path) {
  InputFile file;
  file.path = path;
  std::ifstream in(path, std::ios::binary);
  if (!in) return file;
  uint64_t hash = 14695981039346656037ull;
  int64_t bytes = 0;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof(buffer)) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      hash = (hash ^ static_cast<unsigned char>(buffer[i])) * 1099511628211ull;
    }
    bytes += in.gcount();
  }
  char hex[17];
  std::snprintf(hex, sizeof(hex), "%016llx", static_cast<unsigned long long>(hash));
  file.bytes = bytes;
  file.fnv1a64 = hex;
  return file;
}

std::string UtcNow() {
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

nlohmann::json ResultUnits(bool metric) {
  const std::string length = metric ? "m" : "master odometry unit";
  return {{"q_wxyz", "unit quaternion (w, x, y, z): slave frame -> master frame"},
          {"C", length + ": slave camera centre in the master frame"},
          {"scale", "slave odometry unit -> master odometry unit"},
          {"std.rot_deg", "deg"},
          {"std.pos", length},
          {"std.axis", length},
          {"errors.rot_deg", "deg"},
          {"errors.dir_deg", "deg"},
          {"errors.dist_pct", "%"},
          {"errors.scale_pct", "%"},
          {"errors.trans_err", "master odometry unit"},
          {"errors.trans_err_m", "m"},
          {"time_offset_s", "s: slave stamp - master clock"}};
}

nlohmann::json ProvenanceToJson(const Provenance& p) {
  nlohmann::json inputs = nlohmann::json::array();
  for (const InputFile& f : p.inputs) {
    inputs.push_back({{"path", f.path}, {"bytes", f.bytes}, {"fnv1a64", f.fnv1a64}});
  }
  return {{"schema_version", p.schema_version},
          {"rigcal", p.rigcal_version},
          {"date_utc", p.date_utc},
          {"command", p.command},
          {"inputs", inputs},
          {"config", p.config},
          {"units", ResultUnits(p.metric)}};
}

std::string ProvenanceToYaml(const Provenance& p) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "provenance" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "schema_version" << YAML::Value << p.schema_version;
  out << YAML::Key << "rigcal" << YAML::Value << p.rigcal_version;
  out << YAML::Key << "date_utc" << YAML::Value << p.date_utc;
  out << YAML::Key << "command" << YAML::Value << p.command;
  out << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
  for (const InputFile& f : p.inputs) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "path" << YAML::Value << f.path << YAML::Key
        << "bytes" << YAML::Value << f.bytes << YAML::Key << "fnv1a64" << YAML::Value << f.fnv1a64
        << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "config" << YAML::Value << p.config;
  out << YAML::Key << "units" << YAML::Value << YAML::BeginMap;
  const nlohmann::json units = ResultUnits(p.metric);  // outlives the loop over its items
  for (const auto& [field, unit] : units.items()) {
    out << YAML::Key << field << YAML::Value << unit.get<std::string>();
  }
  out << YAML::EndMap << YAML::EndMap << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace rigcal::io
