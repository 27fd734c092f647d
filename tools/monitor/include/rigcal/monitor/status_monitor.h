// SPDX-License-Identifier: Apache-2.0
#pragma once
// StatusMonitor: listens to a running calibrator on an LCM bus (RIGCAL_STATUS and
// RIGCAL_EXTRINSICS, validated by MessageValidator; a rejected message is counted, never shown)
// and keeps the newest of each. RunStatusMonitor is `rigcal status`: a dashboard refreshed in
// place, plain lines, or one JSON snapshot with the health as exit code.
//
// Threads: every method on one thread (LCM dispatches on the thread that calls Poll).

#include <atomic>
#include <chrono>
#include <memory>
#include <ostream>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/monitor/status_snapshot.h"

namespace lcm {
class LCM;
}

namespace rigcal::monitor {

class StatusMonitor {
 public:
  // `url`: the LCM URL ("" = LCM's default udpm URL; file:///log?speed=0 reads a log). `lcm`
  // (optional, not owned, must outlive the monitor): listen on this instance instead (memq://
  // tests).
  explicit StatusMonitor(std::string url, ::lcm::LCM* lcm = nullptr);
  ~StatusMonitor();
  StatusMonitor(const StatusMonitor&) = delete;
  StatusMonitor& operator=(const StatusMonitor&) = delete;

  // Opens LCM and subscribes. The error names the URL. Call once.
  [[nodiscard]] Status Open();
  // Handles the messages arriving within `timeout` (returns early after the first one).
  // Returns the number handled; -1 when LCM failed.
  int Poll(std::chrono::milliseconds timeout);
  // The newest messages and their ages now.
  MonitorSnapshot Snapshot() const;

  // The channel handler (public for LCM's C-style callback; not part of the API).
  void Handle(const std::string& channel, const void* data, int64_t size);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct StatusRunOptions {
  std::string url;           // see StatusMonitor
  bool lcm_network = false;  // allow a url that reaches other hosts (bus_exposure.h)
  bool once = false;         // print one snapshot and exit with the health code
  bool json = false;         // the snapshot as JSON (SnapshotToJson), one object per line
  double timeout_s = 5.0;    // --once: wait at most this long for the messages (> 0)
  bool ansi = false;         // refresh a terminal screen in place (AnsiFrame); else plain lines
  double refresh_s = 1.0;    // seconds between screen refreshes (> 0)
  int width = 0;             // terminal columns to cut lines at (0 = none)
};

// Runs `rigcal status`. --once: listens until a RIGCAL_STATUS and a RIGCAL_EXTRINSICS arrived
// (or timeout_s passed), prints the snapshot (JSON, or the dashboard text) and returns its
// Health code (0 converged, 1 converging, 2 decalibrated, 3 no data). Otherwise until `stop`:
// with `ansi` the dashboard redrawn in place every refresh_s; without it, whenever a new
// RIGCAL_STATUS arrived, the dashboard as plain lines (or one JSON line with `json`) after a
// "---" line; returns the last Health code. An LCM that cannot be opened: the message on `err`
// and 3 (no data can arrive; 1 would read as "converging" to a health check).
int RunStatusMonitor(const StatusRunOptions& options, std::ostream& out, std::ostream& err,
                     const std::atomic<bool>& stop, ::lcm::LCM* lcm = nullptr);

}  // namespace rigcal::monitor
