// SPDX-License-Identifier: Apache-2.0
#pragma once
// Tests that run other programs (unshare, lcm-logger, ...) beside the rigcal binary
// (cli/command_test.h), and the rule for what cannot run here: skipped with the reason, a failure
// under CI=true.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "cli/command_test.h"

namespace rigcal::support {

// Runs `command` with /bin/sh, stdout and stderr captured through files in `dir`.
inline cli_test::RunResult RunShell(const std::string& command, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "shell_stdout.txt";
  const std::filesystem::path err = dir / "shell_stderr.txt";
  const std::string line = "(" + command + ") >" + cli_test::Quote(out.string()) + " 2>" +
                           cli_test::Quote(err.string()) + " </dev/null";
  const int status = std::system(line.c_str());
  cli_test::RunResult result;
  result.exit_code = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
  result.out = cli_test::Slurp(out);
  result.err = cli_test::Slurp(err);
  return result;
}

// True when the environment variable CI is "true".
inline bool InCi() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

}  // namespace rigcal::support

// Skips the current test with `reason`, or fails it under CI=true (CI must run everything).
#define RIGCAL_SKIP_UNLESS_CI(reason)                                 \
  do {                                                                \
    if (::rigcal::support::InCi()) FAIL() << "CI=true: " << (reason); \
    GTEST_SKIP() << (reason);                                         \
  } while (false)
