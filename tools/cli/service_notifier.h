// SPDX-License-Identifier: Apache-2.0
#pragma once
// ServiceNotifier: the systemd service protocol of the calibrator's unit (config/systemd,
// Type=notify): READY=1 once start-up is done, WATCHDOG=1 at half the period systemd asks for
// (WATCHDOG_USEC, only for the process WATCHDOG_PID names when it is set), STOPPING=1 on a clean
// stop. Everything goes through libsystemd's sd_notify; without a NOTIFY_SOCKET (not started
// by systemd) or in a build without libsystemd (RIGCAL_WITH_SYSTEMD unset) every call does
// nothing. Threads: one thread calls everything (the node's loop).

#include <chrono>
#include <string>

namespace rigcal::cli {

class ServiceNotifier {
 public:
  // Reads the watchdog period from the environment (sd_watchdog_enabled).
  ServiceNotifier();

  // READY=1 with a STATUS= line for `systemctl status`.
  void Ready(const std::string& status);
  // WATCHDOG=1 when half the watchdog period has passed since the last one; cheap otherwise.
  // Call it from the loop whose progress proves the service alive.
  void Tick();
  // STOPPING=1: a stop was requested and the service is saving its state.
  void Stopping();

  // The watchdog period systemd asked for, 0 when none.
  std::chrono::microseconds watchdog_period() const { return watchdog_period_; }
  // Whether this build can notify systemd at all (linked with libsystemd).
  static bool Supported();

 private:
  std::chrono::microseconds watchdog_period_{0};
  std::chrono::steady_clock::time_point last_ping_{};
};

}  // namespace rigcal::cli
