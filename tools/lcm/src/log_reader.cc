// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/log_reader.h"

#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>

#include "rigcal/lcm/log_writer.h"

namespace rigcal::lcm {
namespace {

constexpr uint32_t kSyncWord = 0xEDA1DA01u;
constexpr int64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

uint64_t BigEndian(const uint8_t* p, int bytes) {
  uint64_t v = 0;
  for (int i = 0; i < bytes; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

namespace {

// Opens one file of a log; its size through *size.
Expected<std::FILE*> OpenPart(const std::string& path, int64_t* size) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    return Error{path + ": cannot open the LCM log: " + std::strerror(errno)};
  }
  *size = -1;
  if (std::fseek(file, 0, SEEK_END) == 0) *size = std::ftell(file);
  if (*size < 0 || std::fseek(file, 0, SEEK_SET) != 0) {
    std::fclose(file);
    return Error{path + ": cannot read the LCM log (not a regular file?)"};
  }
  return file;
}

bool IsRegularFile(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISREG(info.st_mode);
}

// The parts of a log split by size (`lcm-logger --split-mb`, `rigcal record --split-mb`):
// PATH.00, PATH.01, ... while they exist; empty when PATH.00 does not exist.
std::vector<std::string> SplitParts(const std::string& path) {
  std::vector<std::string> parts;
  while (IsRegularFile(LogPartPath(path, static_cast<int>(parts.size())))) {
    parts.push_back(LogPartPath(path, static_cast<int>(parts.size())));
  }
  return parts;
}

}  // namespace

Expected<std::unique_ptr<LogReader>> LogReader::Open(const std::string& path,
                                                     LogReaderOptions options) {
  struct stat info {};
  std::vector<std::string> parts;
  if (::stat(path.c_str(), &info) != 0 && errno == ENOENT) parts = SplitParts(path);
  if (!parts.empty()) {
    const int n = static_cast<int>(parts.size());
    for (int k = n + 1; k <= n + 10; ++k) {
      if (IsRegularFile(LogPartPath(path, k))) {
        return Error{LogPartPath(path, n) + ": missing part of a split LCM log (" +
                     LogPartPath(path, k) + " exists)"};
      }
    }
  }
  if (parts.empty()) parts = {path};
  int64_t total = 0;
  for (const std::string& part : parts) {
    if (::stat(part.c_str(), &info) == 0) total += info.st_size;
  }
  int64_t size = 0;
  auto file = OpenPart(parts.front(), &size);
  if (!file) return Error{file.error()};
  auto reader = std::unique_ptr<LogReader>(new LogReader(parts.front(), *file, size, options));
  reader->parts_ = std::move(parts);
  reader->total_size_ = std::max(total, size);
  return reader;
}

LogReader::LogReader(std::string path, std::FILE* file, int64_t size, LogReaderOptions options)
    : path_(std::move(path)), file_(file), size_(size), options_(options) {}

bool LogReader::NextPart(std::string* error) {
  if (part_ + 1 >= parts_.size()) return false;
  int64_t size = 0;
  auto file = OpenPart(parts_[part_ + 1], &size);
  if (!file) {
    *error = file.error();
    return false;
  }
  std::fclose(file_);
  file_ = *file;
  ++part_;
  done_bytes_ += position_;
  path_ = parts_[part_];
  size_ = size;
  position_ = 0;
  return true;
}

LogReader::~LogReader() {
  if (file_ != nullptr) std::fclose(file_);
}

LogReader::Outcome LogReader::Damaged(int64_t offset, const std::string& what) {
  problem_ = path_ + ": byte " + std::to_string(offset) + ": " + what;
  finished_ = true;
  final_outcome_ = Outcome::kDamaged;
  return final_outcome_;
}

LogReader::Outcome LogReader::Next(LogEvent* event) { return Read(event, true); }

LogReader::Outcome LogReader::NextHeader(LogEvent* event) { return Read(event, false); }

LogReader::Outcome LogReader::Read(LogEvent* event, bool with_data) {
  if (finished_) return final_outcome_;
  const int64_t start = position_;
  std::array<uint8_t, kHeaderBytes> header{};
  const size_t got = std::fread(header.data(), 1, header.size(), file_);
  if (got == 0 && std::feof(file_)) {
    std::string error;
    if (NextPart(&error)) return Read(event, with_data);
    if (!error.empty()) return Damaged(start, "end of this part, and the next: " + error);
    finished_ = true;
    final_outcome_ = Outcome::kEnd;
    return final_outcome_;
  }
  if (got < header.size()) {
    return Damaged(start, "truncated event header (" + std::to_string(got) + " of " +
                              std::to_string(kHeaderBytes) + " bytes)");
  }
  const auto sync = static_cast<uint32_t>(BigEndian(header.data(), 4));
  if (sync != kSyncWord) {
    char text[64];
    std::snprintf(text, sizeof(text), "no event sync word (0x%08X instead of 0x%08X)", sync,
                  kSyncWord);
    return Damaged(start, text);
  }
  const auto event_number = static_cast<int64_t>(BigEndian(header.data() + 4, 8));
  const auto timestamp = static_cast<int64_t>(BigEndian(header.data() + 12, 8));
  const auto channel_len = static_cast<int32_t>(BigEndian(header.data() + 20, 4));
  const auto data_len = static_cast<int32_t>(BigEndian(header.data() + 24, 4));
  if (channel_len <= 0 || channel_len > options_.max_channel_bytes) {
    return Damaged(start, "channel length " + std::to_string(channel_len) + " outside [1, " +
                              std::to_string(options_.max_channel_bytes) + "]");
  }
  if (data_len < 0 || data_len > options_.max_event_bytes) {
    return Damaged(start, "data length " + std::to_string(data_len) + " outside [0, " +
                              std::to_string(options_.max_event_bytes) + "] bytes");
  }
  const int64_t left = size_ - start - kHeaderBytes;
  if (int64_t{channel_len} + data_len > left) {
    return Damaged(start, "truncated event: " + std::to_string(channel_len + int64_t{data_len}) +
                              " bytes announced, " + std::to_string(left) + " left in the file");
  }
  event->channel.resize(static_cast<size_t>(channel_len));
  event->data.resize(with_data ? static_cast<size_t>(data_len) : 0);
  if (std::fread(event->channel.data(), 1, event->channel.size(), file_) != event->channel.size()) {
    return Damaged(start, "read failed inside the event");
  }
  if (with_data ? std::fread(event->data.data(), 1, event->data.size(), file_) != event->data.size()
                : std::fseek(file_, data_len, SEEK_CUR) != 0) {
    return Damaged(start, "read failed inside the event");
  }
  for (const char c : event->channel) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
      return Damaged(start, "channel name with a non-printable byte");
    }
  }
  event->event_number = event_number;
  event->timestamp_us = timestamp;
  event->offset = start;
  position_ = start + kHeaderBytes + channel_len + data_len;
  return Outcome::kEvent;
}

}  // namespace rigcal::lcm
