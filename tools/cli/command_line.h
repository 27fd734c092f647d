// SPDX-License-Identifier: Apache-2.0
#pragma once
// The grammar every subcommand shares, applied in main() before CLI11 parses:
//   - verbosity anywhere on the line, before or after the subcommand: -q/--quiet (warnings and
//     errors only, no progress), -v/--verbose (debug), --log-level LEVEL (or --log-level=LEVEL);
//     the last one given wins; RIGCAL_LOG_LEVEL when none is given;
//   - an unknown subcommand or option is a usage error (exit 2) naming it, with the nearest
//     known name ("did you mean --master?"), before any check of required options runs.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

namespace rigcal::cli {

struct Verbosity {
  std::optional<std::string> log_level;  // from -q, -v or --log-level; nullopt: not given
  bool quiet = false;                    // -q: no progress display either
};

// Removes the verbosity options from `args` (argv without the program name) wherever they
// are and returns them. A --log-level without a value is left for CLI11 to report.
Verbosity ExtractVerbosity(std::vector<std::string>* args);

// Whether -q was given: progress displays stay silent (replay_progress.h and the others).
bool QuietRequested();
void SetQuietRequested(bool quiet);

// The nearest of `candidates` to `word` (edit distance at most 2, or a third of its length),
// empty when none is near.
std::string NearestName(const std::string& word, const std::vector<std::string>& candidates);

// The usage error for the first unknown subcommand or option of `args` ("rigcal: unknown
// subcommand 'slove'; did you mean 'solve'? (rigcal --help lists them)", "rigcal solve: unknown
// option '--mastr'; did you mean '--master'?"), empty when every word is known. Options are
// checked up to a `--`.
std::string UnknownWordError(const CLI::App& app, const std::vector<std::string>& args);

// The program's version and command line (main() sets them), for the provenance of results.
void SetInvocation(const std::string& version, int argc, char** argv);
const std::string& RigcalVersion();
const std::string& CommandLine();

}  // namespace rigcal::cli
