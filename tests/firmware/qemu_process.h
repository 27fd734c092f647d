// SPDX-License-Identifier: Apache-2.0
#pragma once
// Runs the cross-built trigger firmware under `qemu-system-arm -M netduinoplus2` for a test:
// its USART1 on the test's pipes (-serial stdio) or on a pseudo-terminal (-serial pty, whose
// path QEMU prints). The process is the test's own child; Stop() ends it by its pid, and it
// dies with the test (PR_SET_PDEATHSIG).

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <vector>

namespace rigcal::testing {

// The firmware image of this build ("" when the toolchain was missing at configure time).
inline std::string TriggerFirmwareElf() {
#ifdef RIGCAL_TRIGGER_FIRMWARE_ELF
  return RIGCAL_TRIGGER_FIRMWARE_ELF;
#else
  return "";
#endif
}

// The wrap-test image: its µs counter preset 4 s before 2^32 (CMake TRIGGER_TEST_COUNTER_PRESET).
inline std::string TriggerFirmwareWrapTestElf() {
#ifdef RIGCAL_TRIGGER_FIRMWARE_WRAPTEST_ELF
  return RIGCAL_TRIGGER_FIRMWARE_WRAPTEST_ELF;
#else
  return "";
#endif
}

// Why the firmware `elf` cannot run here, or "" when it can.
inline std::string QemuFirmwareMissing(const std::string& elf = TriggerFirmwareElf()) {
  if (elf.empty()) {
    return "arm-none-eabi-g++ was not found when the build was configured, so the trigger "
           "firmware was not built (install gcc-arm-none-eabi libnewlib-arm-none-eabi "
           "libstdc++-arm-none-eabi-newlib: scripts/install-deps.sh)";
  }
  if (access(elf.c_str(), R_OK) != 0) return "firmware image " + elf + " is missing";
  if (std::system("command -v qemu-system-arm >/dev/null 2>&1") != 0) {
    return "qemu-system-arm is not installed (Debian package qemu-system-arm)";
  }
  return "";
}

inline int64_t SteadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

class QemuFirmware {
 public:
  enum class Serial { kStdio, kPty };
  ~QemuFirmware() { Stop(); }

  // Starts QEMU on `elf`. kStdio: Write/Read talk to USART1. kPty: pty_path() names the terminal.
  bool Start(Serial serial, std::string* error, const std::string& elf = TriggerFirmwareElf()) {
    int in[2], out[2], err[2];
    if (pipe(in) != 0 || pipe(out) != 0 || pipe(err) != 0) {
      *error = "pipe failed";
      return false;
    }
    std::vector<std::string> args = {"qemu-system-arm",
                                     "-M",
                                     "netduinoplus2",
                                     "-nographic",
                                     "-monitor",
                                     "none",
                                     "-serial",
                                     serial == Serial::kStdio ? "stdio" : "pty",
                                     "-semihosting-config",
                                     "enable=on,target=native",
                                     "-kernel",
                                     elf};
    pid_ = fork();
    if (pid_ < 0) {
      *error = "fork failed";
      return false;
    }
    if (pid_ == 0) {
      // QEMU dies with the test: a test killed by a sanitizer's abort or a signal runs no
      // destructor, and a firmware left running costs a core for ever (the forking thread is
      // the test's, which lives as long as the process).
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      if (getppid() == 1) _exit(127);
      dup2(in[0], 0);
      dup2(out[1], 1);
      dup2(err[1], 2);
      for (int fd : {in[0], in[1], out[0], out[1], err[0], err[1]}) close(fd);
      std::vector<char*> argv;
      for (std::string& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execvp(argv[0], argv.data());
      _exit(127);
    }
    close(in[0]);
    close(out[1]);
    close(err[1]);
    to_qemu_ = in[1];
    from_qemu_ = out[0];
    stderr_ = err[0];
    fcntl(from_qemu_, F_SETFL, O_NONBLOCK);
    fcntl(stderr_, F_SETFL, O_NONBLOCK);
    if (serial == Serial::kPty) {
      // "char device redirected to /dev/pts/N (label serial0)", on stdout or stderr.
      std::string text;
      const int64_t deadline = SteadyNs() + 10'000'000'000;
      while (SteadyNs() < deadline) {
        pollfd fds[2] = {{from_qemu_, POLLIN, 0}, {stderr_, POLLIN, 0}};
        poll(fds, 2, 100);
        char buf[256];
        for (int fd : {from_qemu_, stderr_}) {
          const ssize_t n = read(fd, buf, sizeof(buf));
          if (n > 0) text.append(buf, static_cast<size_t>(n));
        }
        const size_t at = text.find("/dev/pts/");
        if (at != std::string::npos) {
          const size_t end = text.find_first_of(" \n", at);
          if (end != std::string::npos) {
            pty_path_ = text.substr(at, end - at);
            return true;
          }
        }
      }
      *error = "QEMU did not name its pty: " + text;
      return false;
    }
    return true;
  }

  // Bytes from USART1 (kStdio) that arrive within `timeout_ms`; appends to `out`.
  void Read(std::vector<uint8_t>* out, int timeout_ms) {
    pollfd fd{from_qemu_, POLLIN, 0};
    if (poll(&fd, 1, timeout_ms) <= 0) return;
    uint8_t buf[4096];
    ssize_t n;
    while ((n = read(from_qemu_, buf, sizeof(buf))) > 0) out->insert(out->end(), buf, buf + n);
  }
  bool Write(const std::vector<uint8_t>& bytes) {
    size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = write(to_qemu_, bytes.data() + done, bytes.size() - done);
      if (n <= 0) return false;
      done += static_cast<size_t>(n);
    }
    return true;
  }
  // QEMU's exit status when it has ended by itself, else -1.
  int ExitedWith() {
    if (pid_ <= 0) return exit_status_;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      exit_status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128;
    }
    return exit_status_;
  }
  const std::string& pty_path() const { return pty_path_; }

  void Stop() {
    if (pid_ > 0) {
      kill(pid_, SIGTERM);
      int status = 0;
      waitpid(pid_, &status, 0);
      pid_ = -1;
    }
    for (int* fd : {&to_qemu_, &from_qemu_, &stderr_}) {
      if (*fd >= 0) close(*fd);
      *fd = -1;
    }
  }

 private:
  pid_t pid_ = -1;
  int exit_status_ = -1;
  int to_qemu_ = -1;
  int from_qemu_ = -1;
  int stderr_ = -1;
  std::string pty_path_;
};

}  // namespace rigcal::testing
