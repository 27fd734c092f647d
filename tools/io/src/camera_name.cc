// SPDX-License-Identifier: Apache-2.0
// Camera names (camera_name.h).
#include "rigcal/io/camera_name.h"

namespace rigcal::io {

std::string CameraNameProblem(const std::string& name) {
  if (name == "." || name == "..") return "'" + name + "' cannot name a camera";
  for (size_t i = 0; i < name.size();) {
    const auto byte = static_cast<unsigned char>(name[i]);
    if (byte < 0x20 || byte == 0x7F) return "a control character in a camera name";
    if (byte == '/') return "'/' in a camera name (it becomes a file name)";
    // UTF-8: the sequence's length from its lead byte, then its continuation bytes.
    size_t length = 1;
    if (byte >= 0xF0 && byte <= 0xF4) {
      length = 4;
    } else if (byte >= 0xE0) {
      length = 3;
    } else if (byte >= 0xC2 && byte <= 0xDF) {
      length = 2;
    } else if (byte >= 0x80) {
      return "not UTF-8 text";
    }
    if (byte > 0xF4 || i + length > name.size()) return "not UTF-8 text";
    for (size_t k = 1; k < length; ++k) {
      if ((static_cast<unsigned char>(name[i + k]) & 0xC0) != 0x80) return "not UTF-8 text";
    }
    i += length;
  }
  return "";
}

}  // namespace rigcal::io
