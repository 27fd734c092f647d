// SPDX-License-Identifier: Apache-2.0
#pragma once
// The harness of the tests that run the built rigcal binary (RIGCAL_BINARY, set by
// tests/CMakeLists.txt): a fresh temporary directory per test, kept when the test fails, and
// Run(args) -> exit code, stdout and stderr.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

extern char** environ;

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

// A result without its provenance (io/provenance.h), which names the date and the command line:
// what the determinism checks compare. YAML: the trailing `provenance:` block cut; JSON: the
// top-level "provenance" object removed (the rest keeps its dump(2) layout).
inline std::string YamlWithoutProvenance(const std::string& yaml) {
  const size_t at = yaml.find("\nprovenance:\n");
  return at == std::string::npos ? yaml : yaml.substr(0, at + 1);
}
inline std::string JsonWithoutProvenance(const std::string& json) {
  const size_t start = json.find("\n  \"provenance\": {");
  if (start == std::string::npos) return json;
  const size_t end = json.find("\n  },", start);  // the object's closing line at depth 1
  return end == std::string::npos ? json : json.substr(0, start) + json.substr(end + 5);
}

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

// `binary args...` in the background (stdin and stdout /dev/null, stderr into err_path); its PID,
// -1 when it could not be started.
inline pid_t Spawn(const std::string& binary, const std::vector<std::string>& args,
                   const std::string& err_path) {
  std::vector<std::string> argv_strings = {binary};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, binary.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

// Exit code of `pid` (a child), waiting at most `timeout`; -1 when it did not exit normally in
// time (then it is killed by its PID) or was killed by a signal.
inline int WaitExit(pid_t pid, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  while (std::chrono::steady_clock::now() < end) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  ::waitpid(pid, &status, 0);
  return -1;
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
