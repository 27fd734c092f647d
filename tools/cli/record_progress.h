// SPDX-License-Identifier: Apache-2.0
#pragma once
// The progress and the summary of `rigcal record`: "  12.0 s | 86.4 MB (7.2 MB/s) | frames
// 240 240 | drops 0 | 1 file" through the one progress scheme (progress_line.h: in place on a
// terminal every 0.25 s, log lines above it; one line per second otherwise); the summary of a
// finished recording on stdout.

#include <chrono>
#include <string>

#include "progress_line.h"
#include "rigcal/pipeline/log_recorder.h"

namespace rigcal::cli {

class RecordProgress {
 public:
  RecordProgress();
  // Shows the line when its period has passed since the last one (`force`: now).
  void Update(const pipeline::RecorderStats& stats, bool force = false);
  // Ends the line in place on a terminal.
  void End();
  double elapsed_s() const;

 private:
  ProgressLine line_;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_;
};

// "recorded 60 frames (62 events, 1.2 MB) in 3.0 s to 1 file: ..., CPU 80 % ..." and the files.
void PrintRecordingSummary(const pipeline::RecorderStats& stats, double elapsed_s,
                           double cpu_percent);

}  // namespace rigcal::cli
