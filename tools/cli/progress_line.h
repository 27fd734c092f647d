// SPDX-License-Identifier: Apache-2.0
#pragma once
// The one progress scheme of every command (replay, calib --log, record, ...): on a terminal one
// line redrawn in place, and a log line is written above it (the line is cleared, the log line
// written, the progress redrawn), never onto it; otherwise plain lines, at most one per period.
// -q shows nothing (command_line.h).

#include <string>
#include <vector>

namespace rigcal::cli {

class ProgressLine {
 public:
  ProgressLine();
  ~ProgressLine();  // ends the line (a newline after the last one drawn in place)
  ProgressLine(const ProgressLine&) = delete;
  ProgressLine& operator=(const ProgressLine&) = delete;

  bool tty() const { return tty_; }
  // Shows `text` in place (terminal) or as a line; `final`: the last one.
  void Show(const std::string& text, bool final = false);

 private:
  bool tty_;
  bool shown_ = false;
};

// Registers the module loggers (ModuleLogger) with a sink that writes above an active progress
// line. main() calls it before anything logs.
void InstallProgressAwareLogging(const std::vector<std::string>& modules);

}  // namespace rigcal::cli
