#include "rigcal/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>
#include <vector>

namespace rigcal::tools {
namespace {

std::string ErrnoText(int err) { return std::strerror(err); }

// The directory `path` lives in ("." for a bare file name).
std::filesystem::path DirectoryOf(const std::string& path) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  return dir;
}

}  // namespace

int WriteAllBytes(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::write(fd, data.data(), data.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    data.remove_prefix(static_cast<size_t>(n));
  }
  return 0;
}

AtomicFile::AtomicFile(std::string path, std::string temp_path, int fd)
    : path_(std::move(path)), temp_path_(std::move(temp_path)), fd_(fd) {}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(temp_path_.c_str());
  }
}

AtomicFile::AtomicFile(AtomicFile&& other) noexcept
    : path_(std::move(other.path_)),
      temp_path_(std::move(other.temp_path_)),
      fd_(std::exchange(other.fd_, -1)) {}

AtomicFile& AtomicFile::operator=(AtomicFile&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) {
      ::close(fd_);
      ::unlink(temp_path_.c_str());
    }
    path_ = std::move(other.path_);
    temp_path_ = std::move(other.temp_path_);
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

Expected<AtomicFile> AtomicFile::Create(const std::string& path) {
  if (path.empty()) return Error{"cannot write a file with an empty name"};
  const std::filesystem::path dir = DirectoryOf(path);
  std::string tmp_basename = ".";
  tmp_basename += std::filesystem::path(path).filename().string();
  tmp_basename += ".tmp.XXXXXX";
  const std::string tmp_template = (dir / tmp_basename).string();
  std::vector<char> tmp_name(tmp_template.begin(), tmp_template.end());
  tmp_name.push_back('\0');

  const int fd = ::mkostemp(tmp_name.data(), O_CLOEXEC);
  if (fd < 0) {
    return Error{"cannot write '" + path + "': cannot create a temporary file in '" + dir.string() +
                 "': " + ErrnoText(errno)};
  }
  AtomicFile file(path, std::string(tmp_name.data()), fd);
  if (::fchmod(fd, 0644) != 0) return file.Fail("chmod", errno);
  return file;
}

Status AtomicFile::Fail(const std::string& step, int err) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(temp_path_.c_str());
  return Error{"cannot write '" + path_ + "': " + step + ": " + ErrnoText(err)};
}

Status AtomicFile::Write(std::string_view data) {
  if (fd_ < 0) return Error{"cannot write '" + path_ + "': write: the file is closed"};
  if (const int err = WriteAllBytes(fd_, data); err != 0) return Fail("write", err);
  return Status::Ok();
}

Status AtomicFile::Commit() {
  if (fd_ < 0) return Error{"cannot write '" + path_ + "': commit: the file is closed"};
  if (::fsync(fd_) != 0) return Fail("fsync", errno);
  const int fd = std::exchange(fd_, -1);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(temp_path_.c_str());
    return Error{"cannot write '" + path_ + "': close: " + ErrnoText(err)};
  }
  if (::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    ::unlink(temp_path_.c_str());
    return Error{"cannot write '" + path_ + "': rename: " + ErrnoText(err)};
  }
  // Make the rename itself durable. A failure here leaves a complete file, so it is ignored.
  const int dir_fd = ::open(DirectoryOf(path_).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return Status::Ok();
}

Status WriteFileAtomically(const std::string& path, std::string_view contents) {
  Expected<AtomicFile> file = AtomicFile::Create(path);
  if (!file.ok()) return file.status();
  if (Status status = file->Write(contents); !status.ok()) return status;
  return file->Commit();
}

}  // namespace rigcal::tools
