// SPDX-License-Identifier: Apache-2.0
#pragma once
// StopSignal: while alive, SIGINT, SIGTERM and SIGHUP (the terminal or session went away) set a
// flag instead of killing the process, so long-running subcommands stop cleanly (flush, publish,
// save state, write the result). One instance at a time; the previous handlers are restored on
// destruction.

#include <atomic>
#include <csignal>

namespace rigcal::cli {

class StopSignal {
 public:
  StopSignal();
  ~StopSignal();
  StopSignal(const StopSignal&) = delete;
  StopSignal& operator=(const StopSignal&) = delete;

  const std::atomic<bool>& flag() const;
  // The signal number received, 0 when none.
  int received() const;
};

}  // namespace rigcal::cli
