// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one rule for the files a command writes (its -o/--out, --camchain, --config-out,
// --poses-out, --truth-out, --out-dir contents, --state, a recording): an existing file of the
// same name is replaced, atomically. Said once here, shown at the end of the --help of every
// subcommand that writes files, and in docs/usage.md ("Output files").

#include <CLI/CLI.hpp>

namespace rigcal::cli {

inline constexpr const char* kOutputFilesRule =
    "Output files: an existing file of the same name is replaced (no --force needed), atomically:\n"
    "the new file is written beside it and renamed over it, keeping its permissions; a path that\n"
    "is not a regular file (a directory, a device, a FIFO) is never replaced. A run that produces\n"
    "nothing (no pose set calibrated, no event recorded) leaves an existing file as it was.";

// Adds kOutputFilesRule to the --help of the subcommands of `app` that write files.
void DocumentOutputFiles(CLI::App& app);

}  // namespace rigcal::cli
