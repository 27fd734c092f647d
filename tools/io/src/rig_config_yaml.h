// SPDX-License-Identifier: Apache-2.0
#pragma once
// Private to tools/io: the rig config from a YAML document already loaded (rig_config.cc), and
// the parser of its `source:` section (rig_config_source.cc).

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/io/rig_config.h"
#include "yaml_fields.h"

namespace rigcal::io {

// LoadRigConfig for a file already loaded (LoadYaml), `path` naming it in errors.
Expected<RigConfig> RigConfigFromYaml(const YAML::Node& root, const std::string& path);

// The `source:` section: the devices of image_folders, v4l2 and libcamera sources, or the
// simulated rig (its cameras and true mountings from `cameras:`), into `config`. `entries`: the
// cameras' YAML entries in config->cameras' order. Returns the source type ("" without a
// source section).
Expected<std::string> ParseSourceSection(const FieldReader& r, const YAML::Node& root,
                                         const std::vector<YAML::Node>& entries,
                                         RigConfig* config);

}  // namespace rigcal::io
