#pragma once
// A GoogleTest fixture for tests that run the built rigcal binary: a fresh temporary directory
// per test (kept when the test fails), and `Rigcal(args)` running the binary with stdout and
// stderr captured. The test target must define RIGCAL_BINARY (tests/CMakeLists.txt).

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <string>

#include "support/command_runner.h"

namespace rigcal::support {

class RigcalCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef RIGCAL_BINARY
    FAIL() << "RIGCAL_BINARY is not defined: tests/CMakeLists.txt must pass the rigcal path";
#else
    binary_ = RIGCAL_BINARY;
#endif
    std::string pattern =
        (std::filesystem::path(::testing::TempDir()) / "rigcal_command_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) std::filesystem::remove_all(dir_, ec);
  }
  // `rigcal <args>` (args quoted by the caller, ShellQuote).
  CommandResult Rigcal(const std::string& args) {
    return RunShell(ShellQuote(binary_) + " " + args, dir_);
  }
  // A file in the test's directory.
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::string binary_;
  std::filesystem::path dir_;
};

}  // namespace rigcal::support
