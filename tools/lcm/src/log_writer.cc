// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/log_writer.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <utility>

#include "rigcal/io/atomic_file.h"

namespace rigcal::lcm {
namespace {

using Clock = std::chrono::steady_clock;

constexpr size_t kEventHeaderBytes = 4 + 8 + 8 + 4 + 4;

void PutBigEndian(uint64_t value, int bytes, uint8_t* out) {
  for (int i = bytes - 1; i >= 0; --i) {
    out[i] = static_cast<uint8_t>(value & 0xFF);
    value >>= 8;
  }
}

std::string CannotWrite(const std::string& path, const std::string& step, int err) {
  return "cannot write '" + path + "': " + step + ": " + std::strerror(err);
}

}  // namespace

Status LogWriterOptions::Check() const {
  if (split_bytes < 0) return Error{"split_bytes: must be >= 0"};
  if (!(sync_interval_s >= 0.0)) return Error{"sync_interval_s: must be >= 0"};
  return Status::Ok();
}

std::string LogPartPath(const std::string& path, int part) {
  char suffix[16];
  std::snprintf(suffix, sizeof(suffix), ".%02d", part);
  return path + suffix;
}

// One open file: an AtomicFile (atomic, or the replacement of an existing file until its first
// event) or a descriptor written in place.
struct LogWriter::Part {
  std::string path;
  std::optional<io::AtomicFile> atomic;
  bool replacing = false;  // `atomic` replaces an existing file at the first event
  int fd = -1;
  int64_t bytes = 0;
  Clock::time_point last_sync = Clock::now();
};

LogWriter::LogWriter(std::string path, LogWriterOptions options)
    : path_(std::move(path)), options_(options) {}

LogWriter::~LogWriter() {
  if (part_ && part_->fd >= 0) ::close(part_->fd);
  // An uncommitted atomic part is removed by ~AtomicFile.
}

Expected<std::unique_ptr<LogWriter>> LogWriter::Open(const std::string& path,
                                                     const LogWriterOptions& options) {
  if (const Status status = options.Check(); !status.ok()) {
    return Error{"LogWriterOptions: " + status.message()};
  }
  if (path.empty()) return Error{"cannot write an LCM log with an empty file name"};
  std::unique_ptr<LogWriter> writer(new LogWriter(path, options));
  if (Status status = writer->OpenPart(); !status.ok()) return status;
  return writer;
}

Status LogWriter::OpenPart() {
  const std::string path =
      options_.split_bytes > 0 ? LogPartPath(path_, static_cast<int>(files_.size())) : path_;
  auto part = std::make_unique<Part>();
  part->path = path;
  std::error_code ec;
  if (!options_.overwrite && std::filesystem::exists(path, ec)) {
    return Error{"cannot write '" + path + "': the file exists (not overwritten)"};
  }
  // Replacing an existing log (overwrite): the new one is written next to it and takes its
  // name with its first event, so a recording that records nothing leaves the old log intact.
  const bool replacing =
      !options_.atomic && options_.overwrite && std::filesystem::exists(path, ec);
  if (options_.atomic || replacing) {
    Expected<io::AtomicFile> file = io::AtomicFile::Create(path);
    if (!file) return file.status();
    part->atomic.emplace(std::move(*file));
    part->replacing = replacing;
  } else {
    const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (options_.overwrite ? O_TRUNC : O_EXCL);
    part->fd = ::open(path.c_str(), flags, 0644);
    if (part->fd < 0) return Error{CannotWrite(path, "create", errno)};
  }
  files_.push_back(path);
  part_ = std::move(part);
  return Status::Ok();
}

Status LogWriter::ClosePart() {
  if (!part_) return Status::Ok();
  std::unique_ptr<Part> part = std::move(part_);
  if (part->atomic) {
    // An unfinished replacement without an event: the old file stays (~AtomicFile removes ours).
    if (part->replacing) return Status::Ok();
    return part->atomic->Commit();
  }
  const int fd = std::exchange(part->fd, -1);
  if (::fdatasync(fd) != 0) {
    const int err = errno;
    ::close(fd);
    return Error{CannotWrite(part->path, "fdatasync", err)};
  }
  if (::close(fd) != 0) return Error{CannotWrite(part->path, "close", errno)};
  return Status::Ok();
}

Status LogWriter::Write(std::string_view channel, int64_t utime, const void* data, size_t size) {
  if (failed_ || !part_) return Error{"cannot write '" + path_ + "': the log is closed"};
  if (channel.empty() || channel.size() > static_cast<size_t>(kLcmMaxChannelLength)) {
    return Error{"channel '" + std::string(channel) + "': an LCM channel has 1 to " +
                 std::to_string(kLcmMaxChannelLength) + " characters"};
  }
  if (size > static_cast<size_t>(INT32_MAX) || (size > 0 && data == nullptr)) {
    return Error{std::string(channel) + ": " + std::to_string(size) +
                 " bytes of data cannot be one LCM log event"};
  }
  const size_t event_bytes = kEventHeaderBytes + channel.size() + size;
  if (options_.split_bytes > 0 && part_->bytes > 0 &&
      part_->bytes + static_cast<int64_t>(event_bytes) > options_.split_bytes) {
    Status status = ClosePart();
    if (status.ok()) status = OpenPart();
    if (!status.ok()) {
      failed_ = true;
      return status;
    }
  }
  buffer_.resize(event_bytes);
  uint8_t* out = buffer_.data();
  PutBigEndian(kLcmLogSyncWord, 4, out);
  PutBigEndian(static_cast<uint64_t>(events_), 8, out + 4);
  PutBigEndian(static_cast<uint64_t>(utime), 8, out + 12);
  PutBigEndian(channel.size(), 4, out + 20);
  PutBigEndian(size, 4, out + 24);
  std::memcpy(out + kEventHeaderBytes, channel.data(), channel.size());
  if (size > 0) std::memcpy(out + kEventHeaderBytes + channel.size(), data, size);
  const std::string_view bytes(reinterpret_cast<const char*>(out), event_bytes);

  if (part_->atomic) {
    if (Status status = part_->atomic->Write(bytes); !status.ok()) {
      failed_ = true;
      return status;
    }
    if (part_->replacing) {  // the first event: the new log takes the old one's place
      Expected<int> fd = part_->atomic->CommitAndKeepOpen();
      part_->atomic.reset();
      part_->replacing = false;
      if (!fd) {
        failed_ = true;
        return fd.status();
      }
      part_->fd = *fd;
      part_->last_sync = Clock::now();
    }
  } else {
    if (const int err = io::WriteAllBytes(part_->fd, bytes); err != 0) {
      failed_ = true;
      return Error{CannotWrite(part_->path, "write", err)};
    }
    const Clock::time_point now = Clock::now();
    if (std::chrono::duration<double>(now - part_->last_sync).count() >= options_.sync_interval_s) {
      if (::fdatasync(part_->fd) != 0) {
        failed_ = true;
        return Error{CannotWrite(part_->path, "fdatasync", errno)};
      }
      part_->last_sync = now;
    }
  }
  part_->bytes += static_cast<int64_t>(event_bytes);
  total_bytes_ += static_cast<int64_t>(event_bytes);
  ++events_;
  return Status::Ok();
}

Status LogWriter::Close() {
  if (failed_) return Status::Ok();
  return ClosePart();
}

}  // namespace rigcal::lcm
