// SPDX-License-Identifier: Apache-2.0
#pragma once
// The file behind a file:// output URL, checked once LCM has closed it. LCM's file provider
// writes through stdio: a full disk or a failing device shows only in the flush at close, whose
// error LCM drops, so every publish returns 0 and a short (or empty) log is left behind. The
// file must grow by exactly the events published (an LCM log event is a 28-byte header, the
// channel name and the data); anything else is a failed write, named with the file.

#include <cstdint>
#include <optional>
#include <string>

#include "rigcal/base/status.h"

namespace rigcal::pipeline {

// Ok unless `url` is a file:// URL that LCM would open for reading (no "mode=w" or "mode=a"
// among its options): an output must be written, and reading a device such as /dev/full never
// ends. The error names the URL and the option it lacks.
Status CheckOutputUrl(const std::string& url);

class PublishedFileCheck {
 public:
  // The check of `url` when it is a file:// URL (its path, without "?options"), taken right
  // after the LCM object was created (the file's size then); nullopt for any other URL and for
  // a path that is not a regular file (a device or FIFO has no size to compare).
  static std::optional<PublishedFileCheck> ForUrl(const std::string& url);

  // One event published on `channel` with `data_bytes` of data. One thread at a time.
  void Count(const std::string& channel, int64_t data_bytes);

  // After the LCM object was destroyed (its file closed): ok when the file grew by the bytes
  // counted, else "<path>: <n> of <m> bytes published reached the file (disk full or write
  // failed); the log is incomplete".
  Status Verify() const;

  const std::string& path() const { return path_; }

 private:
  PublishedFileCheck(std::string path, int64_t start_size);

  std::string path_;
  int64_t start_size_ = 0;
  int64_t expected_bytes_ = 0;
};

}  // namespace rigcal::pipeline
