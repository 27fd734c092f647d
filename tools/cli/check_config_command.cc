// SPDX-License-Identifier: Apache-2.0
// `rigcal check-config CONFIG`: the config validated, every live camera opened with its format
// and rate (no capture), the trigger generator's Hello, and what `rigcal run` would run
// (pipeline::CheckRigConfig). Exit 0 when everything is fine, 1 with every problem named.
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/config_check.h"

namespace rigcal::cli {
namespace {

struct CheckConfigArgs {
  std::string config;
  bool no_open = false;
};

int RunCheckConfig(const CheckConfigArgs& args) {
  auto config = io::LoadRigConfig(args.config);
  if (!config) {
    std::cout << "FAIL " << config.error() << "\n";
    return kExitError;
  }
  const pipeline::ConfigCheck check = pipeline::CheckRigConfig(*config, !args.no_open);
  std::cout << args.config << ": valid; rigcal run would run:\n";
  for (const std::string& line : check.plan) std::cout << "  " << line << "\n";
  for (const std::string& problem : check.problems) std::cout << "FAIL " << problem << "\n";
  std::cout << (check.ok() ? "ok" : std::to_string(check.problems.size()) + " problem(s)") << "\n";
  return check.ok() ? kExitOk : kExitError;
}

}  // namespace

void RegisterCheckConfig(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<CheckConfigArgs>();
  CLI::App* cmd = app.add_subcommand(
      "check-config",
      "Checks a rig config before driving: validates it (errors name the file, line and key),\n"
      "opens every camera with its format and rate and closes it again (no capture), asks the\n"
      "trigger generator for its Hello, and prints what `rigcal run` would run. Exit 0 when\n"
      "everything is fine, 1 with every problem on a FAIL line.");
  cmd->add_option("config", args->config, "The rig config YAML")->required();
  cmd->add_flag("--no-open", args->no_open,
                "Validate and plan only: do not open the cameras or the trigger's port");
  cmd->callback([args, exit_code]() { *exit_code = RunCheckConfig(*args); });
}

}  // namespace rigcal::cli
