// SPDX-License-Identifier: Apache-2.0
#pragma once
// The events of an LCM log file as LCM's own reader (::lcm::LogFile) returns them: it stops at the
// first incomplete or corrupt event. Header-only: for GoogleTest targets that link LCM.

#include <gtest/gtest.h>

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <vector>

namespace rigcal::support {

struct LoggedEvent {
  int64_t eventnum = 0;
  int64_t timestamp = 0;  // µs
  std::string channel;
  std::vector<uint8_t> data;
  bool operator==(const LoggedEvent& other) const {
    return channel == other.channel && data == other.data;
  }
};

// Every event of `path`; a test failure and no event when the file cannot be opened.
inline std::vector<LoggedEvent> ReadLcmLog(const std::string& path) {
  std::vector<LoggedEvent> events;
  ::lcm::LogFile log(path, "r");
  if (!log.good()) {
    ADD_FAILURE() << path << ": cannot open the LCM log";
    return events;
  }
  while (const ::lcm::LogEvent* e = log.readNextEvent()) {
    const auto* data = static_cast<const uint8_t*>(e->data);
    events.push_back(
        {e->eventnum, e->timestamp, e->channel, std::vector<uint8_t>(data, data + e->datalen)});
  }
  return events;
}

}  // namespace rigcal::support
