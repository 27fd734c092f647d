// SPDX-License-Identifier: Apache-2.0
#pragma once
// Progress of a replay on stderr: a bar redrawn in place with the ETA on a terminal, a plain
// line every few seconds otherwise (logs, CI); log lines go above the bar (progress_line.h).

#include <chrono>
#include <string>

#include "progress_line.h"
#include "rigcal/pipeline/calib_node.h"

namespace rigcal::cli {

class ReplayProgressDisplay {
 public:
  // `label` starts every line ("rigcal replay").
  explicit ReplayProgressDisplay(std::string label);
  // Shows `progress` (called about every 0.2 s, and once with done = true).
  void Update(const pipeline::ReplayProgress& progress);

 private:
  std::string label_;
  ProgressLine line_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point next_line_;
};

// "1:05" / "1:02:03" for a number of seconds.
std::string ClockText(double seconds);

}  // namespace rigcal::cli
