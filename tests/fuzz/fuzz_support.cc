// SPDX-License-Identifier: Apache-2.0
#include "fuzz_support.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

#include "rigcal/base/logging.h"

namespace rigcal::fuzz {

InputFile::InputFile(const std::string& name) {
  struct stat st {};
  std::string base = "/tmp";
  if (const char* tmp = std::getenv("TMPDIR"); tmp != nullptr && *tmp != '\0') base = tmp;
  if (stat("/dev/shm", &st) == 0 && S_ISDIR(st.st_mode) && access("/dev/shm", W_OK) == 0) {
    base = "/dev/shm";
  }
  std::string templ = base + "/rigcal-fuzz-XXXXXX";
  std::vector<char> buffer(templ.begin(), templ.end());
  buffer.push_back('\0');
  if (mkdtemp(buffer.data()) == nullptr) {
    std::perror("rigcal fuzz: mkdtemp");
    std::abort();
  }
  dir_ = buffer.data();
  path_ = dir_ + "/" + name;
}

InputFile::~InputFile() {
  unlink(path_.c_str());
  rmdir(dir_.c_str());
}

const std::string& InputFile::Write(const uint8_t* data, size_t size) {
  const int fd = open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) {
    std::perror(("rigcal fuzz: open " + path_).c_str());
    std::abort();
  }
  size_t done = 0;
  while (done < size) {
    const ssize_t n = write(fd, data + done, size - done);
    if (n <= 0) {
      std::perror(("rigcal fuzz: write " + path_).c_str());
      std::abort();
    }
    done += static_cast<size_t>(n);
  }
  close(fd);
  return path_;
}

void QuietLogs() { SetLogLevel("off"); }

void PropertyFailed(const std::string& what) {
  std::fprintf(stderr, "rigcal fuzz: property broken: %s\n", what.c_str());
  std::abort();
}

}  // namespace rigcal::fuzz
