#include "rigcal/io/atomic_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <vector>

namespace rigcal::tools {
namespace {

std::string ErrnoText(int err) { return std::strerror(err); }

// Writes all of `data`, retrying short writes and EINTR. Returns 0 or an errno value.
int WriteAll(int fd, std::string_view data) {
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

}  // namespace

std::string WriteFileAtomically(const std::string& path, std::string_view contents) {
  if (path.empty()) return "cannot write a file with an empty name";
  const std::filesystem::path target(path);
  std::filesystem::path dir = target.parent_path();
  if (dir.empty()) dir = ".";
  std::string tmp_basename = ".";
  tmp_basename += target.filename().string();
  tmp_basename += ".tmp.XXXXXX";
  const std::string tmp_template = (dir / tmp_basename).string();
  std::vector<char> tmp_name(tmp_template.begin(), tmp_template.end());
  tmp_name.push_back('\0');

  const int fd = ::mkostemp(tmp_name.data(), O_CLOEXEC);
  if (fd < 0) {
    return "cannot write '" + path + "': cannot create a temporary file in '" + dir.string() +
           "': " + ErrnoText(errno);
  }
  auto fail = [&](const std::string& step, int err) {
    ::close(fd);
    ::unlink(tmp_name.data());
    return "cannot write '" + path + "': " + step + ": " + ErrnoText(err);
  };
  if (::fchmod(fd, 0644) != 0) return fail("chmod", errno);
  if (const int err = WriteAll(fd, contents); err != 0) return fail("write", err);
  if (::fsync(fd) != 0) return fail("fsync", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(tmp_name.data());
    return "cannot write '" + path + "': close: " + ErrnoText(err);
  }
  if (::rename(tmp_name.data(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(tmp_name.data());
    return "cannot write '" + path + "': rename: " + ErrnoText(err);
  }
  // Make the rename itself durable. A failure here leaves a complete file, so it is ignored.
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return "";
}

}  // namespace rigcal::tools
