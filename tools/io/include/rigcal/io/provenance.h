// SPDX-License-Identifier: Apache-2.0
#pragma once
// Where a result came from: written into every result YAML and JSON and the report, so a file
// found later says which rigcal made it, when, from which inputs, and in which units.
//
// YAML (a `provenance:` map beside the slaves; readers skip it):
//   provenance:
//     schema_version: 2
//     rigcal: 0.1.0 (abc1234)          # version and commit
//     date_utc: 2026-12-06T06:00:00Z
//     command: rigcal replay drive.lcmlog --config rig.yaml -o result.yaml
//     inputs: [{path: drive.lcmlog, bytes: 1234, fnv1a64: 0123456789abcdef}, ...]
//     config: rig.yaml
//     units: {C: ..., scale: ..., q_wxyz: ..., std.rot_deg: deg, ...}

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace rigcal::io {

// The version of the result schema (result YAML and JSON): 2 added the provenance.
inline constexpr int kResultSchemaVersion = 2;

struct InputFile {
  std::string path;
  int64_t bytes = -1;   // -1: not a readable regular file
  std::string fnv1a64;  // FNV-1a 64 of the content, 16 hex digits (identifies, not a signature)
};

struct Provenance {
  int schema_version = kResultSchemaVersion;
  std::string rigcal_version;  // "0.1.0 (git describe)"
  std::string date_utc;        // ISO 8601, seconds
  std::string command;         // the command line, words joined by spaces
  std::vector<InputFile> inputs;
  std::string config;   // the rig config's path, empty without one
  bool metric = false;  // C in metres (else in the master odometry's unit)
};

// The file's size and hash (bytes -1 and an empty hash when it cannot be read).
InputFile DescribeInput(const std::string& path);

// The current UTC time as ISO 8601 ("2026-12-06T06:00:00Z").
std::string UtcNow();

// The unit of every field of a result, by field name.
nlohmann::json ResultUnits(bool metric);

nlohmann::json ProvenanceToJson(const Provenance& provenance);

// The `provenance:` block as YAML text (ends with a newline).
std::string ProvenanceToYaml(const Provenance& provenance);

}  // namespace rigcal::io
