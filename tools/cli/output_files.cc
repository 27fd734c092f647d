// SPDX-License-Identifier: Apache-2.0
#include "output_files.h"

#include <set>
#include <string>

namespace rigcal::cli {

namespace {

void AppendRule(CLI::App* cmd) {
  const std::string footer = cmd->get_footer();
  cmd->footer(footer.empty() ? kOutputFilesRule : footer + "\n\n" + kOutputFilesRule);
}

}  // namespace

void DocumentOutputFiles(CLI::App& app) {
  // The subcommands with an option naming a file or folder to write (tests/cli/output_files_test
  // writes over an existing file with each).
  static const std::set<std::string> kWriters = {"solve",  "experiment", "run",    "calib",
                                                 "replay", "synth-log",  "report", "record",
                                                 "import", "intrinsics", "vo"};
  for (CLI::App* sub : app.get_subcommands({})) {
    if (kWriters.count(sub->get_name()) == 0) continue;
    AppendRule(sub);
    for (CLI::App* nested : sub->get_subcommands({})) AppendRule(nested);  // import euroc, tum
  }
}

}  // namespace rigcal::cli
