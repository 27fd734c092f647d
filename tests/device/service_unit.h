// SPDX-License-Identifier: Apache-2.0
#pragma once
// What a test needs of a systemd service unit file (config/systemd/*.service.in as installed):
// its Environment= assignments, its settings, and its ExecStart= command line expanded the way
// systemd expands it (systemd.service(5) "Command lines"): "${VAR}" is one word, "$VAR" alone
// splits into words (none when empty), "${VAR}" inside a word is replaced in place; the
// prefixes @ - : + ! are dropped. Only what the project's units use: one ExecStart= line,
// Environment= values without quotes.

#include <map>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::device_test {

struct ServiceUnit {
  std::map<std::string, std::string> environment;  // Environment=KEY=VALUE, in order of lines
  std::map<std::string, std::string> settings;     // every other Key=value of [Service] (last)
  std::string exec_start;                          // ExecStart= as written

  // ExecStart= split into words with `environment` (the unit's Environment=, overridden by the
  // caller as an EnvironmentFile= would) substituted.
  std::vector<std::string> ExpandExecStart(
      const std::map<std::string, std::string>& environment) const;
  // A setting of [Service], empty when the unit has none.
  std::string Setting(const std::string& key) const {
    const auto it = settings.find(key);
    return it == settings.end() ? std::string() : it->second;
  }
};

// Reads a unit file; an error names the file and line of what cannot be read.
Expected<ServiceUnit> ReadServiceUnit(const std::string& path);

// A systemd time span in seconds ("20s", "1min 30s", "500ms", "20" = seconds); NaN when it is
// not one.
double SystemdSpanSeconds(const std::string& span);

}  // namespace rigcal::device_test
