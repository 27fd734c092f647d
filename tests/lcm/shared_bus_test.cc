// SPDX-License-Identifier: Apache-2.0
// SharedBus: threads that publish on one file:// bus at once leave a log whose every event is
// whole (LCM's file provider alone interleaves their bytes and damages the log).
#include "rigcal/lcm/shared_bus.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/lcm/log_reader.h"

namespace rigcal::lcm {
namespace {

namespace fs = std::filesystem;

// Message k of thread t: 4 + (k * 37 + t * 101) % 900 bytes, the first two t and k % 256, the
// rest t.
std::vector<uint8_t> Payload(int t, int k) {
  std::vector<uint8_t> bytes(static_cast<size_t>(4 + (k * 37 + t * 101) % 900),
                             static_cast<uint8_t>(t));
  bytes[1] = static_cast<uint8_t>(k % 256);
  return bytes;
}

TEST(SharedBus, ThreadsPublishingOnAFileBusLeaveEveryEventWhole) {
  const std::string path =
      (fs::temp_directory_path() / ("rigcal_shared_bus_" + std::to_string(::getpid()) + ".lcmlog"))
          .string();
  constexpr int kThreads = 4;
  constexpr int kMessages = 3000;
  {
    ::lcm::LCM bus("file://" + path + "?mode=w");
    ASSERT_TRUE(bus.good());
    SharedBus shared(&bus);
    std::vector<std::thread> threads;
    threads.reserve(kThreads);
    std::vector<int> failures(kThreads, 0);
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&shared, &failures, t] {
        const std::string channel = "CH" + std::to_string(t);
        for (int k = 0; k < kMessages; ++k) {
          if (shared.Publish(channel, Payload(t, k)) != 0) ++failures[static_cast<size_t>(t)];
        }
      });
    }
    for (std::thread& thread : threads) thread.join();
    for (int t = 0; t < kThreads; ++t) EXPECT_EQ(failures[static_cast<size_t>(t)], 0) << t;
  }

  auto reader = LogReader::Open(path);
  ASSERT_TRUE(reader) << reader.error();
  std::map<std::string, int> next;  // per channel: the index of the next message
  LogEvent event;
  int events = 0;
  LogReader::Outcome outcome;
  while ((outcome = (*reader)->Next(&event)) == LogReader::Outcome::kEvent) {
    ++events;
    ASSERT_EQ(event.channel.rfind("CH", 0), 0u) << event.channel;
    const int t = std::stoi(event.channel.substr(2));
    const int k = next[event.channel]++;
    ASSERT_EQ(event.data, Payload(t, k)) << "message " << k << " of " << event.channel;
  }
  EXPECT_EQ(outcome, LogReader::Outcome::kEnd) << (*reader)->problem();
  EXPECT_EQ(events, kThreads * kMessages);
  fs::remove(path);
}

}  // namespace
}  // namespace rigcal::lcm
