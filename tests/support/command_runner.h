#pragma once
// Tests that run programs (the built rigcal binary, lcm-logger, ...): a shell command with its
// stdout and stderr captured, and the rule for what cannot run here: skipped with the reason, a
// failure under CI=true.

#include <filesystem>
#include <string>

namespace rigcal::support {

struct CommandResult {
  int exit_code = -1;  // -1 when the command did not exit normally
  std::string out;
  std::string err;
};

// The whole file as text ("" when it cannot be read).
std::string Slurp(const std::filesystem::path& path);

// Runs `command` with /bin/sh, stdout and stderr captured through files in `dir`.
CommandResult RunShell(const std::string& command, const std::filesystem::path& dir);

// "'text'" with every ' escaped, for a shell command line.
std::string ShellQuote(const std::string& text);

// True when the environment variable CI is "true".
bool InCi();

}  // namespace rigcal::support

// Skips the current test with `reason`, or fails it under CI=true (CI must run everything).
#define RIGCAL_SKIP_UNLESS_CI(reason)                                 \
  do {                                                                \
    if (::rigcal::support::InCi()) FAIL() << "CI=true: " << (reason); \
    GTEST_SKIP() << (reason);                                         \
  } while (false)
