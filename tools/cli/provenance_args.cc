// SPDX-License-Identifier: Apache-2.0
#include "provenance_args.h"

#include "command_line.h"

namespace rigcal::cli {

io::Provenance ProvenanceOf(const std::vector<std::string>& inputs, const std::string& config,
                            bool metric) {
  io::Provenance p;
  p.rigcal_version = RigcalVersion();
  p.date_utc = io::UtcNow();
  p.command = CommandLine();
  p.config = config;
  p.metric = metric;
  for (const std::string& path : inputs) {
    if (!path.empty()) p.inputs.push_back(io::DescribeInput(path));
  }
  if (!config.empty()) p.inputs.push_back(io::DescribeInput(config));
  return p;
}

}  // namespace rigcal::cli
