// SPDX-License-Identifier: Apache-2.0
#pragma once
// The check of a rig config against this computer before driving (`rigcal check-config`): every
// live camera opened with its format and rate and closed again (no frame grabbed), the trigger
// generator asked for its Hello, and a plan of what `rigcal run` would do. Every problem is
// named by the config file and the key it comes from.

#include <string>
#include <vector>

#include "rigcal/io/rig_config.h"

namespace rigcal::pipeline {

struct ConfigCheck {
  std::vector<std::string> plan;      // what `rigcal run` would run, one line each
  std::vector<std::string> problems;  // "<file>:<line>: cameras[1] 'right'.device: <why>"
  bool ok() const { return problems.empty(); }
};

// `open_devices` false: the plan only (a config written for another computer).
ConfigCheck CheckRigConfig(const io::RigConfig& config, bool open_devices);

}  // namespace rigcal::pipeline
