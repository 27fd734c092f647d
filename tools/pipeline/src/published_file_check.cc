// SPDX-License-Identifier: Apache-2.0
#include "published_file_check.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace rigcal::pipeline {
namespace {

// sync word (4), event number (8), timestamp (8), channel length (4), data length (4).
constexpr int64_t kEventHeaderBytes = 28;

// The size of `path`, or -1 with *err set; *regular: whether it is a regular file.
int64_t SizeOf(const std::string& path, int* err, bool* regular = nullptr) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    *err = errno;
    return -1;
  }
  if (regular != nullptr) *regular = S_ISREG(st.st_mode);
  return static_cast<int64_t>(st.st_size);
}

}  // namespace

Status CheckOutputUrl(const std::string& url) {
  constexpr std::string_view kScheme = "file://";
  if (url.compare(0, kScheme.size(), kScheme) != 0) return Status::Ok();
  const size_t options = url.find('?');
  const std::string query = options == std::string::npos ? "" : "&" + url.substr(options + 1);
  if (query.find("&mode=w") != std::string::npos || query.find("&mode=a") != std::string::npos) {
    return Status::Ok();
  }
  return Error{url + ": an output file:// URL needs ?mode=w (LCM opens it for reading otherwise)"};
}

PublishedFileCheck::PublishedFileCheck(std::string path, int64_t start_size)
    : path_(std::move(path)), start_size_(start_size) {}

std::optional<PublishedFileCheck> PublishedFileCheck::ForUrl(const std::string& url) {
  constexpr std::string_view kScheme = "file://";
  if (url.compare(0, kScheme.size(), kScheme) != 0) return std::nullopt;
  std::string path = url.substr(kScheme.size());
  if (const size_t options = path.find('?'); options != std::string::npos) path.resize(options);
  int err = 0;
  bool regular = false;
  const int64_t size = SizeOf(path, &err, &regular);
  if (size >= 0 && !regular) return std::nullopt;  // a device or FIFO has no size to check
  return PublishedFileCheck(std::move(path), size < 0 ? 0 : size);
}

void PublishedFileCheck::Count(const std::string& channel, int64_t data_bytes) {
  expected_bytes_ += kEventHeaderBytes + static_cast<int64_t>(channel.size()) + data_bytes;
}

Status PublishedFileCheck::Verify() const {
  int err = 0;
  const int64_t size = SizeOf(path_, &err);
  if (size < 0) {
    return Error{path_ + ": the published LCM log cannot be checked: " + std::strerror(err)};
  }
  const int64_t written = size - start_size_;
  if (written == expected_bytes_) return Status::Ok();
  return Error{path_ + ": " + std::to_string(written < 0 ? 0 : written) + " of " +
               std::to_string(expected_bytes_) +
               " bytes published reached the file (disk full or write failed); the log is "
               "incomplete"};
}

}  // namespace rigcal::pipeline
