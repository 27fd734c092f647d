// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <utility>
#include <vector>

namespace rigcal::io {
namespace {

std::string ErrnoText(int err) { return std::strerror(err); }

// The directory `path` lives in ("." for a bare file name).
std::filesystem::path DirectoryOf(const std::string& path) {
  std::filesystem::path dir = std::filesystem::path(path).parent_path();
  if (dir.empty()) dir = ".";
  return dir;
}

// What a non-regular file is, for the error message.
const char* KindOf(mode_t mode) {
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Ok when `path` may be replaced: it does not exist, or it is a regular file (lstat: a symbolic
// link is not followed). *mode gets the permission bits the new file keeps (the existing file's,
// else `new_file_mode`).
Status CheckReplaceable(const std::string& path, mode_t new_file_mode, mode_t* mode) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    const int err = errno;
    if (err == ENOENT) {
      *mode = new_file_mode;
      return Status::Ok();
    }
    return Error{"cannot write '" + path + "': " + ErrnoText(err)};
  }
  if (!S_ISREG(st.st_mode)) {
    return Error{"cannot write '" + path + "': it is " + KindOf(st.st_mode) +
                 ", not a regular file (rigcal replaces only regular files)"};
  }
  *mode = st.st_mode & 07777;
  return Status::Ok();
}

// The temporary files of `path` are ".<name>.tmp.<pid>.XXXXXX" in its directory: the writer's
// process id tells a leftover of a killed writer (no such process) from a write in progress.
std::string TempPrefix(const std::string& path) {
  return "." + std::filesystem::path(path).filename().string() + ".tmp.";
}

// Removes the temporary files of `path` whose writer no longer exists (a process killed while it
// wrote: kill -9, power loss). Best effort: a file that cannot be removed stays.
void RemoveLeftovers(const std::string& path) {
  const std::string prefix = TempPrefix(path);
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(DirectoryOf(path), ec)) {
    const std::string name = entry.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string rest = name.substr(prefix.size());
    const size_t dot = rest.find('.');
    if (dot == 0 || dot == std::string::npos) continue;
    char* end = nullptr;
    const long pid = std::strtol(rest.c_str(), &end, 10);
    if (end != rest.c_str() + dot || pid <= 0) continue;
    if (::kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;  // alive (or not ours)
    std::filesystem::remove(entry.path(), ec);
  }
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

Expected<AtomicFile> AtomicFile::Create(const std::string& path, unsigned new_file_mode) {
  if (path.empty()) return Error{"cannot write a file with an empty name"};
  mode_t mode = kNewFileMode;
  if (Status status = CheckReplaceable(path, new_file_mode & 07777, &mode); !status.ok()) {
    return status;
  }
  const std::filesystem::path dir = DirectoryOf(path);
  RemoveLeftovers(path);
  const std::string tmp_basename = TempPrefix(path) + std::to_string(::getpid()) + ".XXXXXX";
  const std::string tmp_template = (dir / tmp_basename).string();
  std::vector<char> tmp_name(tmp_template.begin(), tmp_template.end());
  tmp_name.push_back('\0');

  const int fd = ::mkostemp(tmp_name.data(), O_CLOEXEC);
  if (fd < 0) {
    return Error{"cannot write '" + path + "': cannot create a temporary file in '" + dir.string() +
                 "': " + ErrnoText(errno)};
  }
  AtomicFile file(path, std::string(tmp_name.data()), fd);
  if (::fchmod(fd, mode) != 0) return file.Fail("chmod", errno);
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
  return RenameOverPath();
}

Expected<int> AtomicFile::CommitAndKeepOpen() {
  if (fd_ < 0) return Error{"cannot write '" + path_ + "': commit: the file is closed"};
  if (::fsync(fd_) != 0) return Fail("fsync", errno);
  const int fd = std::exchange(fd_, -1);
  if (Status status = RenameOverPath(); !status.ok()) {
    ::close(fd);
    return status;
  }
  return fd;
}

Status AtomicFile::RenameOverPath() {
  // Checked again: the path may have become something else while the contents were written.
  mode_t mode = kNewFileMode;
  if (Status status = CheckReplaceable(path_, kNewFileMode, &mode); !status.ok()) {
    ::unlink(temp_path_.c_str());
    return status;
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

Status WriteFileAtomically(const std::string& path, std::string_view contents,
                           unsigned new_file_mode) {
  Expected<AtomicFile> file = AtomicFile::Create(path, new_file_mode);
  if (!file.ok()) return file.status();
  if (Status status = file->Write(contents); !status.ok()) return status;
  return file->Commit();
}

Status CheckReplaceable(const std::string& path) {
  mode_t mode = kNewFileMode;
  return CheckReplaceable(path, kNewFileMode, &mode);
}

Expected<KeptAside> KeepAside(const std::string& path, const std::string& tag) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    return Error{"cannot keep '" + path + "' aside: " + ErrnoText(errno)};
  }
  if (!S_ISREG(st.st_mode)) {
    return Error{"cannot keep '" + path + "' aside: it is " + KindOf(st.st_mode) +
                 ", not a regular file (rigcal moves only regular files)"};
  }
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  ::gmtime_r(&now, &utc);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y%m%dT%H%M%SZ", &utc);
  const std::string base = path + "." + tag + "-" + stamp;
  std::string aside = base;
  for (int n = 2; ::access(aside.c_str(), F_OK) == 0; ++n) aside = base + "-" + std::to_string(n);
  if (::rename(path.c_str(), aside.c_str()) != 0) {
    return Error{"cannot keep '" + path + "' as '" + aside + "': " + ErrnoText(errno)};
  }
  return KeptAside{aside, static_cast<unsigned>(st.st_mode & 07777)};
}

}  // namespace rigcal::io
