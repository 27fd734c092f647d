// SPDX-License-Identifier: Apache-2.0
// LogReader against logs written by ::lcm::LogFile: the same events, and damage (a cut file, a
// corrupt sync word, an absurd length) reported with its byte offset instead of being skipped or
// allocated.
#include "rigcal/lcm/log_reader.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>

namespace rigcal::lcm {
namespace {

namespace fs = std::filesystem;

class LogReaderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    path_ = (fs::temp_directory_path() /
             ("rigcal_log_reader_" + std::to_string(::getpid()) + "_" +
              ::testing::UnitTest::GetInstance()->current_test_info()->name()))
                .string();
  }
  void TearDown() override { fs::remove(path_); }

  // Writes `count` events with ::lcm::LogFile: channel CH<k % 3>, k + 1 bytes of value k.
  // Returns the byte offset of every event.
  std::vector<int64_t> WriteEvents(int count) {
    std::vector<int64_t> offsets;
    ::lcm::LogFile log(path_, "w");
    EXPECT_TRUE(log.good());
    for (int k = 0; k < count; ++k) {
      offsets.push_back(static_cast<int64_t>(std::ftell(log.getFilePtr())));
      std::vector<uint8_t> data(static_cast<size_t>(k + 1), static_cast<uint8_t>(k));
      ::lcm::LogEvent event;
      event.eventnum = k;
      event.timestamp = 1000 * k + 7;
      event.channel = "CH" + std::to_string(k % 3);
      event.datalen = static_cast<int32_t>(data.size());
      event.data = data.data();
      EXPECT_EQ(log.writeEvent(&event), 0);
    }
    return offsets;
  }

  void Append(const std::vector<uint8_t>& bytes) {
    std::ofstream out(path_, std::ios::binary | std::ios::app);
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  }

  std::unique_ptr<LogReader> Open(LogReaderOptions options = {}) {
    auto reader = LogReader::Open(path_, options);
    EXPECT_TRUE(reader) << reader.error();
    return reader ? std::move(*reader) : nullptr;
  }

  // Reads until the end or the damage; returns the number of events.
  int ReadAll(LogReader* reader, LogReader::Outcome* last) {
    LogEvent event;
    int n = 0;
    while ((*last = reader->Next(&event)) == LogReader::Outcome::kEvent) ++n;
    return n;
  }

  std::string path_;
};

TEST_F(LogReaderTest, ReadsWhatLcmWrote) {
  const std::vector<int64_t> offsets = WriteEvents(20);
  auto reader = Open();
  ASSERT_NE(reader, nullptr);
  LogEvent event;
  for (int k = 0; k < 20; ++k) {
    ASSERT_EQ(reader->Next(&event), LogReader::Outcome::kEvent) << reader->problem();
    EXPECT_EQ(event.event_number, k);
    EXPECT_EQ(event.timestamp_us, 1000 * k + 7);
    EXPECT_EQ(event.channel, "CH" + std::to_string(k % 3));
    EXPECT_EQ(event.data,
              std::vector<uint8_t>(static_cast<size_t>(k + 1), static_cast<uint8_t>(k)));
    EXPECT_EQ(event.offset, offsets[static_cast<size_t>(k)]);
  }
  EXPECT_EQ(reader->Next(&event), LogReader::Outcome::kEnd);
  EXPECT_EQ(reader->Next(&event), LogReader::Outcome::kEnd);
  EXPECT_EQ(reader->position(), reader->size());
  EXPECT_TRUE(reader->problem().empty());
}

TEST_F(LogReaderTest, HeadersOnlyScanSeesEveryChannel) {
  WriteEvents(7);
  auto reader = Open();
  LogEvent event;
  int n = 0;
  while (reader->NextHeader(&event) == LogReader::Outcome::kEvent) {
    EXPECT_EQ(event.channel, "CH" + std::to_string(n % 3));
    EXPECT_TRUE(event.data.empty());
    ++n;
  }
  EXPECT_EQ(n, 7);
}

TEST_F(LogReaderTest, TruncatedEventIsReportedAtItsOffset) {
  const std::vector<int64_t> offsets = WriteEvents(10);
  fs::resize_file(path_, fs::file_size(path_) - 3);  // inside the last event's data
  auto reader = Open();
  LogReader::Outcome last;
  EXPECT_EQ(ReadAll(reader.get(), &last), 9);
  EXPECT_EQ(last, LogReader::Outcome::kDamaged);
  EXPECT_NE(reader->problem().find("byte " + std::to_string(offsets[9]) + ": truncated"),
            std::string::npos)
      << reader->problem();
  EXPECT_EQ(reader->position(), offsets[9]);

  // A cut inside the header too.
  fs::resize_file(path_, static_cast<uintmax_t>(offsets[9] + 10));
  reader = Open();
  EXPECT_EQ(ReadAll(reader.get(), &last), 9);
  EXPECT_EQ(last, LogReader::Outcome::kDamaged);
  EXPECT_NE(reader->problem().find("truncated event header"), std::string::npos)
      << reader->problem();
}

TEST_F(LogReaderTest, CorruptSyncWordStopsThereInsteadOfSkipping) {
  const std::vector<int64_t> offsets = WriteEvents(10);
  {
    std::fstream f(path_, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(offsets[4]);
    f.put('\x42');
  }
  auto reader = Open();
  LogReader::Outcome last;
  EXPECT_EQ(ReadAll(reader.get(), &last), 4);
  EXPECT_EQ(last, LogReader::Outcome::kDamaged);
  EXPECT_NE(reader->problem().find("byte " + std::to_string(offsets[4]) + ": no event sync word"),
            std::string::npos)
      << reader->problem();
}

TEST_F(LogReaderTest, OversizedLengthsAreRejectedBeforeAllocation) {
  WriteEvents(3);
  const int64_t bad = static_cast<int64_t>(fs::file_size(path_));
  // A header announcing 2 GiB - 1 of data (::lcm::LogFile would try to allocate it).
  Append({0xED, 0xA1, 0xDA, 0x01, 0, 0, 0, 0, 0, 0,    0,    3,    0,    0,   0,
          0,    0,    0,    0,    9, 0, 0, 0, 2, 0x7F, 0xFF, 0xFF, 0xFF, 'C', 'H'});
  LogReaderOptions options;
  options.max_event_bytes = 1 << 20;
  auto reader = Open(options);
  LogReader::Outcome last;
  EXPECT_EQ(ReadAll(reader.get(), &last), 3);
  EXPECT_EQ(last, LogReader::Outcome::kDamaged);
  EXPECT_NE(reader->problem().find("byte " + std::to_string(bad) + ": data length 2147483647"),
            std::string::npos)
      << reader->problem();

  // Within the limit but beyond the end of the file: truncated, still without allocating it.
  options.max_event_bytes = int64_t{1} << 31;
  reader = Open(options);
  EXPECT_EQ(ReadAll(reader.get(), &last), 3);
  EXPECT_NE(reader->problem().find("2147483649 bytes announced"), std::string::npos)
      << reader->problem();
}

TEST_F(LogReaderTest, EmptyAndMissingFiles) {
  std::ofstream(path_).close();
  auto reader = Open();
  LogEvent event;
  EXPECT_EQ(reader->Next(&event), LogReader::Outcome::kEnd);
  auto missing = LogReader::Open(path_ + ".missing");
  ASSERT_FALSE(missing);
  EXPECT_NE(missing.error().find(path_ + ".missing"), std::string::npos) << missing.error();
}

}  // namespace
}  // namespace rigcal::lcm
