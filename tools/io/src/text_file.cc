// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/text_file.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>

namespace rigcal::io {

Expected<std::string> ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};
  std::ostringstream contents;
  contents << in.rdbuf();
  if (in.bad()) return Error{path + ": read error"};
  return contents.str();
}

}  // namespace rigcal::io
