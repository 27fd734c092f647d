// SPDX-License-Identifier: Apache-2.0
// LogWriter: the bytes of lcm-logger's format, reading back through LCM's own reader, splitting,
// atomic parts, and what is left readable after a crash cut the file inside an event.
#include "rigcal/lcm/log_writer.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/log_reader.h"
#include "rigcal/lcm/pose_log.h"
#include "rigcal/lcm/pose_message.h"
#include "support/lcm_log_events.h"
#include "support/temp_dir.h"

namespace rigcal::lcm {
namespace {

namespace fs = std::filesystem;

using support::LoggedEvent;

std::vector<uint8_t> FileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

std::vector<uint8_t> Payload(size_t size, uint8_t seed) {
  std::vector<uint8_t> data(size);
  for (size_t i = 0; i < size; ++i) data[i] = static_cast<uint8_t>(seed + i * 7);
  return data;
}

TEST(LogWriter, WritesLcmLoggerFormat) {
  const std::string path = (support::FreshTempDir("log_writer_format") / "a.lcmlog").string();
  auto writer = LogWriter::Open(path);
  ASSERT_TRUE(writer.ok()) << writer.error();
  const std::vector<uint8_t> data = {1, 2, 3};
  ASSERT_TRUE((*writer)->Write("CH", 0x0102030405060708, data.data(), data.size()).ok());
  ASSERT_TRUE((*writer)->Write("RIGCAL_POSE_cam1", 99, data.data(), 0).ok());
  ASSERT_TRUE((*writer)->Close().ok());
  // sync word, event number 0, timestamp, channel length 2, data length 3, "CH", data.
  const std::vector<uint8_t> first = {0xED, 0xA1, 0xDA, 0x01, 0, 0, 0,   0,   0, 0, 0,
                                      0,    1,    2,    3,    4, 5, 6,   7,   8, 0, 0,
                                      0,    2,    0,    0,    0, 3, 'C', 'H', 1, 2, 3};
  const std::vector<uint8_t> bytes = FileBytes(path);
  ASSERT_GE(bytes.size(), first.size());
  EXPECT_EQ(std::vector<uint8_t>(bytes.begin(), bytes.begin() + first.size()), first);
  EXPECT_EQ(static_cast<int64_t>(bytes.size()), (*writer)->bytes());
  EXPECT_EQ(bytes.size(), first.size() + 28 + 16);

  const std::vector<LoggedEvent> events = support::ReadLcmLog(path);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].channel, "CH");
  EXPECT_EQ(events[0].timestamp, 0x0102030405060708);
  EXPECT_EQ(events[0].data, data);
  EXPECT_EQ(events[1].eventnum, 1);
  EXPECT_EQ(events[1].channel, "RIGCAL_POSE_cam1");
  EXPECT_TRUE(events[1].data.empty());
}

TEST(LogWriter, RejectsBadChannelsAndExistingFiles) {
  const fs::path dir = support::FreshTempDir("log_writer_reject");
  const std::string path = (dir / "a.lcmlog").string();
  auto writer = LogWriter::Open(path);
  ASSERT_TRUE(writer.ok()) << writer.error();
  const uint8_t byte = 0;
  EXPECT_FALSE((*writer)->Write("", 0, &byte, 1).ok());
  const Status long_channel = (*writer)->Write(std::string(64, 'X'), 0, &byte, 1);
  EXPECT_NE(long_channel.message().find("1 to 63 characters"), std::string::npos)
      << long_channel.message();
  EXPECT_TRUE((*writer)->Write(std::string(63, 'X'), 0, &byte, 1).ok());
  ASSERT_TRUE((*writer)->Close().ok());

  auto again = LogWriter::Open(path);
  ASSERT_FALSE(again.ok());
  EXPECT_NE(again.error().find(path), std::string::npos) << again.error();
  EXPECT_NE(again.error().find("exists"), std::string::npos) << again.error();
  // Overwriting: a recording without an event leaves the old log; the first event replaces it.
  const uintmax_t old_size = fs::file_size(path);
  LogWriterOptions overwrite;
  overwrite.overwrite = true;
  auto empty = LogWriter::Open(path, overwrite);
  ASSERT_TRUE(empty.ok()) << empty.error();
  EXPECT_EQ(fs::file_size(path), old_size);
  ASSERT_TRUE((*empty)->Close().ok());
  EXPECT_EQ(fs::file_size(path), old_size);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), {}), 1) << "a temporary file was left";
  auto replaced = LogWriter::Open(path, overwrite);
  ASSERT_TRUE(replaced.ok()) << replaced.error();
  ASSERT_TRUE((*replaced)->Write("A", 0, &byte, 1).ok());
  EXPECT_EQ(fs::file_size(path), 28u + 1u + 1u);  // the new log under the name at once
  ASSERT_TRUE((*replaced)->Write("A", 1, &byte, 1).ok());
  ASSERT_TRUE((*replaced)->Close().ok());
  EXPECT_EQ(fs::file_size(path), 2u * (28u + 1u + 1u));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), {}), 1);

  LogWriterOptions bad;
  bad.split_bytes = -1;
  auto invalid = LogWriter::Open((dir / "b.lcmlog").string(), bad);
  ASSERT_FALSE(invalid.ok());
  EXPECT_NE(invalid.error().find("split_bytes"), std::string::npos) << invalid.error();
}

TEST(LogWriter, SplitsBySizeIntoNumberedParts) {
  const fs::path dir = support::FreshTempDir("log_writer_split");
  const std::string path = (dir / "drive.lcmlog").string();
  LogWriterOptions options;
  options.split_bytes = 1000;
  auto writer = LogWriter::Open(path, options);
  ASSERT_TRUE(writer.ok()) << writer.error();
  const std::vector<uint8_t> data = Payload(300, 5);  // 300 + 28 + 3 bytes per event
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE((*writer)->Write("IMG", 1000 * i, data.data(), data.size()).ok());
  }
  const std::vector<uint8_t> big = Payload(2500, 9);  // larger than a part: a part of its own
  ASSERT_TRUE((*writer)->Write("BIG", 20000, big.data(), big.size()).ok());
  ASSERT_TRUE((*writer)->Close().ok());

  // 3 events (993 bytes) per part: 4 parts for the 10 small ones, then the big one alone.
  const std::vector<std::string> expected = {path + ".00", path + ".01", path + ".02", path + ".03",
                                             path + ".04"};
  EXPECT_EQ((*writer)->files(), expected);
  EXPECT_FALSE(fs::exists(path));
  int64_t next_event = 0;
  int64_t total = 0;
  for (const std::string& part : expected) {
    ASSERT_TRUE(fs::exists(part)) << part;
    total += static_cast<int64_t>(fs::file_size(part));
    if (part != expected.back()) {
      EXPECT_LE(fs::file_size(part), 1000u) << part;
    }
    for (const LoggedEvent& e : support::ReadLcmLog(part))
      EXPECT_EQ(e.eventnum, next_event++) << part;
  }
  EXPECT_EQ(next_event, 11);
  EXPECT_EQ(total, (*writer)->bytes());
  EXPECT_EQ(support::ReadLcmLog(expected.back()).at(0).data, big);
  EXPECT_EQ(LogPartPath("x", 7), "x.07");
  EXPECT_EQ(LogPartPath("x", 123), "x.123");
}

TEST(LogWriter, SplitLogReadsBackAsOneLog) {
  const fs::path dir = support::FreshTempDir("log_writer_split_read");
  const std::string path = (dir / "drive.lcmlog").string();
  LogWriterOptions options;
  options.split_bytes = 1000;
  auto writer = LogWriter::Open(path, options);
  ASSERT_TRUE(writer.ok()) << writer.error();
  for (int i = 0; i < 10; ++i) {
    const std::vector<uint8_t> data = Payload(300, i);
    ASSERT_TRUE((*writer)->Write("IMG", 1000 * i, data.data(), data.size()).ok());
  }
  ASSERT_TRUE((*writer)->Close().ok());
  ASSERT_GE((*writer)->files().size(), 3u);

  // LogReader given the name without a part suffix reads every part in order.
  auto reader = LogReader::Open(path);
  ASSERT_TRUE(reader.ok()) << reader.error();
  LogEvent event;
  int64_t count = 0;
  while ((*reader)->Next(&event) == LogReader::Outcome::kEvent) {
    EXPECT_EQ(event.event_number, count);
    EXPECT_EQ(event.timestamp_us, 1000 * count);
    EXPECT_EQ(event.data, Payload(300, static_cast<int>(count)));
    ++count;
  }
  EXPECT_EQ(count, 10);
  EXPECT_TRUE((*reader)->problem().empty()) << (*reader)->problem();
  EXPECT_EQ((*reader)->position(), (*writer)->bytes());
  EXPECT_EQ((*reader)->size(), (*writer)->bytes());

  // A missing middle part is named, not skipped.
  fs::remove(LogPartPath(path, 1));
  auto gap = LogReader::Open(path);
  ASSERT_FALSE(gap.ok());
  EXPECT_NE(gap.error().find(LogPartPath(path, 1)), std::string::npos) << gap.error();
}

TEST(LogWriter, AtomicPartAppearsOnlyWhenClosed) {
  const fs::path dir = support::FreshTempDir("log_writer_atomic");
  const std::string path = (dir / "import.lcmlog").string();
  LogWriterOptions options;
  options.atomic = true;
  {
    auto writer = LogWriter::Open(path, options);
    ASSERT_TRUE(writer.ok()) << writer.error();
    const std::vector<uint8_t> data = Payload(10, 1);
    ASSERT_TRUE((*writer)->Write("A", 1, data.data(), data.size()).ok());
    EXPECT_FALSE(fs::exists(path));
    // Destroyed without Close: nothing appears, no temporary file is left.
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_TRUE(fs::is_empty(dir));
  auto writer = LogWriter::Open(path, options);
  ASSERT_TRUE(writer.ok()) << writer.error();
  const std::vector<uint8_t> data = Payload(10, 1);
  ASSERT_TRUE((*writer)->Write("A", 1, data.data(), data.size()).ok());
  ASSERT_TRUE((*writer)->Close().ok());
  EXPECT_EQ(support::ReadLcmLog(path).size(), 1u);
}

// Power loss or a crash cuts the file anywhere: every event before the cut reads back, the torn
// one and nothing after it.
TEST(LogWriter, TruncatedLogReadsUpToLastCompleteEvent) {
  const fs::path dir = support::FreshTempDir("log_writer_truncated");
  const std::string path = (dir / "a.lcmlog").string();
  auto writer = LogWriter::Open(path);
  ASSERT_TRUE(writer.ok()) << writer.error();
  std::vector<int64_t> ends;  // file offset after each event
  for (int i = 0; i < 5; ++i) {
    const std::vector<uint8_t> data = Payload(100 + 10 * i, static_cast<uint8_t>(i));
    ASSERT_TRUE((*writer)->Write("CAM" + std::to_string(i), i, data.data(), data.size()).ok());
    ends.push_back((*writer)->bytes());
  }
  ASSERT_TRUE((*writer)->Close().ok());
  const std::vector<uint8_t> full = FileBytes(path);
  // Cuts inside the 4th event: in its header, in its channel, in its data; and exactly after the
  // 3rd.
  const int64_t start4 = ends[2];
  for (const int64_t cut : {start4 + 3, start4 + 20, start4 + 30, start4 + 60, start4}) {
    const std::string cut_path = (dir / ("cut_" + std::to_string(cut))).string();
    std::ofstream(cut_path, std::ios::binary)
        .write(reinterpret_cast<const char*>(full.data()), cut);
    const std::vector<LoggedEvent> events = support::ReadLcmLog(cut_path);
    ASSERT_EQ(events.size(), 3u) << "cut at byte " << cut;
    EXPECT_EQ(events[2].channel, "CAM2");
    EXPECT_EQ(events[2].data, Payload(120, 2));
  }
}

TEST(PoseLog, WritePoseEventsSortsAndRoundTrips) {
  const fs::path dir = support::FreshTempDir("log_writer_poses");
  const std::string path = (dir / "poses.lcmlog").string();
  const CameraNames names = {"front", "left"};
  std::vector<CameraPose> poses;
  for (int k = 3; k >= 0; --k) {
    for (int cam = 1; cam >= 0; --cam) {
      CameraPose p;
      p.camera = cam;
      p.t_ns = 1'000'000'000 + k * 50'000'000 + cam * 1'000'000 * (k % 2);
      p.pose.C = Eigen::Vector3d(k, cam, 1);
      p.segment = cam * k;
      poses.push_back(p);
    }
  }
  ASSERT_TRUE(WritePoseEvents(path, names, poses).ok());
  MessageValidator validator(names);
  int64_t last_t = -1;
  int last_camera = -1;
  const std::vector<LoggedEvent> events = support::ReadLcmLog(path);
  ASSERT_EQ(events.size(), poses.size());
  for (const LoggedEvent& e : events) {
    auto pose = validator.DecodeCameraPose(e.channel, e.data.data(), e.data.size());
    ASSERT_TRUE(pose.ok()) << pose.error();
    const CameraPose& p = pose->pose;
    EXPECT_EQ(e.channel, PoseChannel(names[p.camera]));
    EXPECT_EQ(e.timestamp, p.t_ns / 1000);
    EXPECT_TRUE(p.t_ns > last_t || (p.t_ns == last_t && p.camera > last_camera));
    EXPECT_EQ(p.segment, p.camera * static_cast<int>(p.pose.C.x()));
    last_t = p.t_ns;
    last_camera = p.camera;
  }
  // A pose of a camera the names do not have is an error naming the path.
  poses[0].camera = 5;
  const Status bad = WritePoseEvents(path, names, poses);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find(path), std::string::npos) << bad.message();
}

}  // namespace
}  // namespace rigcal::lcm
