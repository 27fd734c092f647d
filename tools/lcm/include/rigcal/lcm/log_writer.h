// SPDX-License-Identifier: Apache-2.0
#pragma once
// LogWriter: writes LCM log files in the format of lcm-logger (read by lcm-logplayer, ::lcm::LogFile
// and `rigcal calib --log`). Every event is, big-endian:
//
//   uint32 sync word 0xEDA1DA01 | int64 event number | int64 timestamp (µs) |
//   int32 channel length | int32 data length | channel bytes | data bytes
//
// Crash safety. Each event is built whole in memory and handed to the kernel in one write, so a
// crash of the process never leaves half an event; the file is fdatasync'ed every
// sync_interval_s, so after a power loss the log is readable up to its last complete event (a
// reader stops at a torn last event). With `atomic` (imports) a part appears under its name only
// once complete (tools/io atomic_file.h) and nothing is synced before.
//
// Splitting. With split_bytes > 0 a new part starts before an event that would take the current
// part beyond split_bytes (a part holds at least one event); the parts are named as lcm-logger
// -i --split-mb names them: FILE.00, FILE.01, ... (LogPartPath). Event numbers continue across
// parts. Without splitting the log is FILE itself.
//
// Threads: one thread at a time (not thread-safe).

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::lcm {

inline constexpr uint32_t kLcmLogSyncWord = 0xEDA1DA01;
// LCM's longest channel name (LCM_MAX_CHANNEL_NAME_LENGTH).
inline constexpr int kLcmMaxChannelLength = 63;

struct LogWriterOptions {
  int64_t split_bytes = 0;       // >= 0; 0 = one file, never split
  double sync_interval_s = 1.0;  // >= 0; seconds between fdatasync calls (0 = after every event)
  bool atomic = false;           // parts appear complete or not at all (see above)
  // Replace existing files (otherwise an existing file is an error): the new file is written
  // next to the old one and replaces it with its first event (synced), so a recording that
  // records nothing leaves the old file; only a regular file is replaced (atomic_file.h).
  bool overwrite = false;
  // Success, or "<field>: <constraint>".
  Status Check() const;
};

// The file of part `part` (0, 1, ...) of a log written to `path` with split_bytes > 0:
// "<path>.00", "<path>.01", ..., "<path>.100" beyond 99.
std::string LogPartPath(const std::string& path, int part);

class LogWriter {
 public:
  // Creates the first file. Errors name the file and the failing step (exists, create, ...), or
  // the invalid option.
  static Expected<std::unique_ptr<LogWriter>> Open(const std::string& path,
                                                   const LogWriterOptions& options = {});
  ~LogWriter();  // closes without committing an atomic part (it is removed)
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  // Appends one event at `utime` (µs). Errors: an empty or longer than kLcmMaxChannelLength
  // channel, data beyond INT32_MAX bytes, a failed write (naming the file and errno text); after
  // a failed write the writer is closed and every later call fails.
  [[nodiscard]] Status Write(std::string_view channel, int64_t utime, const void* data,
                             size_t size);
  // Syncs (or commits) and closes the current part. Idempotent.
  [[nodiscard]] Status Close();

  int64_t events() const { return events_; }
  int64_t bytes() const { return total_bytes_; }  // all parts
  // Every file started so far, in order.
  const std::vector<std::string>& files() const { return files_; }

 private:
  struct Part;
  LogWriter(std::string path, LogWriterOptions options);
  Status OpenPart();
  Status ClosePart();

  std::string path_;
  LogWriterOptions options_;
  std::unique_ptr<Part> part_;
  std::vector<std::string> files_;
  std::vector<uint8_t> buffer_;  // the event being written
  int64_t events_ = 0;
  int64_t total_bytes_ = 0;
  bool failed_ = false;
};

}  // namespace rigcal::lcm
