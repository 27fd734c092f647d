// SPDX-License-Identifier: Apache-2.0
#pragma once
// The part `rigcal run`, `calib` and `replay` share: load the config, run a CalibNode until it
// ends (Ctrl-C / SIGTERM stop it cleanly), speak the service protocol when live, show the
// progress of a replay, print and write the result, and map it to the exit code (0 every slave
// usable, 3 some slave not, 1 bad input).

#include <CLI/CLI.hpp>
#include <string>

#include "rigcal/pipeline/calib_node.h"

namespace rigcal::cli {

struct NodeRunArgs {
  std::string command;    // "run", "calib" or "replay": names the command in messages
  std::string config;     // rig config YAML
  std::string camchain;   // Kalibr-style camchain written at the end; empty = none
  bool json = false;      // the result as JSON (rigcal solve --json schema) on stdout
  bool progress = false;  // replay: a progress bar on a TTY, progress lines otherwise (stderr)
  bool eval = false;      // capture of a simulated source: print the errors against its truth
};

// The options run, calib and replay share: --config, --out, --camchain, --json, --state,
// --resume.
void AddNodeOptions(CLI::App* cmd, NodeRunArgs* run, pipeline::CalibNodeOptions* node);

// Runs the node; returns the process exit code.
int RunCalibNode(const NodeRunArgs& args, pipeline::CalibNodeOptions options);

}  // namespace rigcal::cli
