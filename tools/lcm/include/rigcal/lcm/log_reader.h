// SPDX-License-Identifier: Apache-2.0
#pragma once
// LogReader: reads the events of an LCM log file (the lcm-logger format) one at a time, and
// stops at the first damage with its byte offset instead of skipping ahead.
//
// Event layout (big-endian): sync word 0xEDA1DA01, int64 event number, int64 timestamp [µs],
// int32 channel length, int32 data length, channel bytes, data bytes. ::lcm::LogFile of LCM 1.3
// resynchronises silently on the next sync word after damage and allocates the data length
// read from the header before reading the data; this reader checks every length against
// limits and against the bytes left in the file BEFORE allocating.
//
// Threads: one thread uses a reader at a time.

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::lcm {

struct LogEvent {
  int64_t event_number = 0;
  int64_t timestamp_us = 0;  // the logger's receive time
  std::string channel;
  std::vector<uint8_t> data;  // reused between events by Next
  int64_t offset = 0;         // byte offset of the event's sync word in the file
};

struct LogReaderOptions {
  // Largest data length accepted [bytes]; a longer event is damage (no allocation is tried).
  // 64 MiB holds an uncompressed 4K RGB image.
  int64_t max_event_bytes = int64_t{64} << 20;
  // Largest channel name accepted (LCM's limit is 255; lcm-logger writes < 1000).
  int32_t max_channel_bytes = 1000;
};

class LogReader {
 public:
  enum class Outcome {
    kEvent,    // *event holds the next event
    kEnd,      // clean end of the file after a complete event
    kDamaged,  // truncated or corrupt event; problem() says where and why; no further events
  };

  // Opens `path`; when no file `path` exists but `path`.00 does, the parts `path`.00, .01, ...
  // of a log split by size are read one after the other as one log. The error names the file.
  static Expected<std::unique_ptr<LogReader>> Open(const std::string& path,
                                                   LogReaderOptions options = {});
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  // Reads the next event into *event (its buffers are reused). After kEnd or kDamaged every
  // call returns the same outcome.
  Outcome Next(LogEvent* event);
  // As Next, but reads only the header and channel and skips the data (event->data is left
  // empty): a quick scan of what a log holds.
  Outcome NextHeader(LogEvent* event);

  // "<path>: byte <offset>: <what>" after kDamaged, else empty.
  const std::string& problem() const { return problem_; }
  // Bytes consumed so far (after the last complete event) and the log's size, over every part.
  int64_t position() const { return done_bytes_ + position_; }
  int64_t size() const { return std::max(total_size_, size_); }
  // The file being read (the current part of a split log).
  const std::string& path() const { return path_; }

 private:
  LogReader(std::string path, std::FILE* file, int64_t size, LogReaderOptions options);
  Outcome Damaged(int64_t offset, const std::string& what);
  Outcome Read(LogEvent* event, bool with_data);
  // At the clean end of a part: opens the next one; false when there is none or it cannot be
  // opened (then *error says why).
  bool NextPart(std::string* error);

  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t size_ = 0;
  LogReaderOptions options_;
  int64_t position_ = 0;
  std::string problem_;
  bool finished_ = false;
  Outcome final_outcome_ = Outcome::kEnd;
  std::vector<std::string> parts_;  // the files of the log (one unless split by size)
  size_t part_ = 0;
  int64_t done_bytes_ = 0;  // bytes of the parts before the current one
  int64_t total_size_ = 0;
};

}  // namespace rigcal::lcm
