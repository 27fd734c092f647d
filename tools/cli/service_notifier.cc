// SPDX-License-Identifier: Apache-2.0
#include "service_notifier.h"

#if defined(RIGCAL_WITH_SYSTEMD)
#include <systemd/sd-daemon.h>
#endif

#include <cstdint>

namespace rigcal::cli {
namespace {

void Notify(const std::string& state) {
#if defined(RIGCAL_WITH_SYSTEMD)
  // < 0: the socket is unusable; 0: not started by systemd. Neither stops the service.
  sd_notify(0, state.c_str());
#else
  (void)state;
#endif
}

}  // namespace

ServiceNotifier::ServiceNotifier() {
#if defined(RIGCAL_WITH_SYSTEMD)
  uint64_t usec = 0;
  if (sd_watchdog_enabled(0, &usec) > 0) watchdog_period_ = std::chrono::microseconds(usec);
#endif
}

bool ServiceNotifier::Supported() {
#if defined(RIGCAL_WITH_SYSTEMD)
  return true;
#else
  return false;
#endif
}

void ServiceNotifier::Ready(const std::string& status) {
  Notify("READY=1\nSTATUS=" + status);
  last_ping_ = std::chrono::steady_clock::now();
  if (watchdog_period_.count() > 0) Notify("WATCHDOG=1");
}

void ServiceNotifier::Tick() {
  if (watchdog_period_.count() <= 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_ping_ >= watchdog_period_ / 2) {
    Notify("WATCHDOG=1");
    last_ping_ = now;
  }
}

void ServiceNotifier::Stopping() { Notify("STOPPING=1"); }

}  // namespace rigcal::cli
