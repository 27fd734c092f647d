#pragma once
// The harness of the tests that run the built rigcal binary (RIGCAL_BINARY, set by
// tests/CMakeLists.txt): a fresh temporary directory per test, kept when the test fails, and
// Run(args) -> exit code, stdout and stderr.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace rigcal::cli_test {

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
  // "exit N", stdout and stderr, for failure messages.
  std::string Explain() const {
    return "exit " + std::to_string(exit_code) + "\n--- stdout:\n" + out + "\n--- stderr:\n" + err;
  }
};

inline std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::string Quote(const std::string& s) { return "'" + s + "'"; }

// Runs `command` (a shell command line) with stdin from /dev/null, stdout and stderr captured in
// files of `dir`.
inline RunResult RunShell(const std::string& command, const std::filesystem::path& dir) {
  const std::string out = (dir / "stdout.txt").string();
  const std::string err = (dir / "stderr.txt").string();
  const int status =
      std::system((command + " >" + Quote(out) + " 2>" + Quote(err) + " </dev/null").c_str());
  RunResult r;
  r.exit_code = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
  r.out = Slurp(out);
  r.err = Slurp(err);
  return r;
}

class CommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef RIGCAL_BINARY
    FAIL() << "RIGCAL_BINARY is not defined: tests/CMakeLists.txt must pass the rigcal path";
#else
    binary_ = RIGCAL_BINARY;
    ASSERT_TRUE(std::filesystem::exists(binary_)) << binary_;
#endif
    std::string pattern =
        (std::filesystem::path(::testing::TempDir()) / "rigcal_command_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    if (HasFailure()) {
      std::cerr << "test files kept in " << dir_ << "\n";
      return;
    }
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  // Runs `rigcal <args>` (a shell command line) with stdin from /dev/null.
  RunResult Run(const std::string& args) const {
    return RunShell(Quote(binary_) + " " + args, dir_);
  }

  std::string binary_;
  std::filesystem::path dir_;
};

// A 2-camera rig config (rig.yaml: master front, slave left with its true mounting) and an
// 800-set synthetic pose log of it (poses.lcmlog, written by rigcal synth-log).
class SynthLogTest : public CommandTest {
 protected:
  void SetUp() override {
    CommandTest::SetUp();
    if (HasFatalFailure()) return;
    std::ofstream(Path("rig.yaml"))
        << "rig: {name: test, master: front}\n"
           "cameras:\n"
           "  - name: front\n"
           "  - name: left\n"
           "    truth: {q_wxyz: [0.9238795, 0, 0.3826834, 0], C: [0.3, 0.05, -0.2]}\n"
           "publish: {extrinsics_rate_hz: 2, status_rate_hz: 1}\n";
    const RunResult synth = Run("synth-log --config " + Path("rig.yaml") + " --out " +
                                Path("poses.lcmlog") + " --frames 800");
    ASSERT_EQ(synth.exit_code, 0) << synth.err;
  }
};

}  // namespace rigcal::cli_test
