// SPDX-License-Identifier: Apache-2.0
#include "v4l2_node.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

namespace rigcal::capture::v4l2 {
namespace {

std::string Text(const uint8_t* bytes, size_t size) {
  const auto* chars = reinterpret_cast<const char*>(bytes);
  return std::string(chars, strnlen(chars, size));
}

// /dev/videoN paths in numeric order.
std::vector<std::string> VideoNodes() {
  std::vector<std::pair<int, std::string>> nodes;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator("/dev", error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("video", 0) != 0 || name.size() == 5) continue;
    const std::string number = name.substr(5);
    if (!std::all_of(number.begin(), number.end(), ::isdigit)) continue;
    nodes.emplace_back(std::stoi(number), entry.path().string());
  }
  std::sort(nodes.begin(), nodes.end());
  std::vector<std::string> paths;
  for (auto& node : nodes) paths.push_back(std::move(node.second));
  return paths;
}

}  // namespace

int Ioctl(int fd, unsigned long request, void* arg) {
  int result;
  do {
    result = ioctl(fd, request, arg);
  } while (result == -1 && errno == EINTR);
  return result;
}

Expected<NodeInfo> QueryNode(int fd) {
  v4l2_capability cap{};
  if (Ioctl(fd, VIDIOC_QUERYCAP, &cap) != 0) {
    return Error{std::string("VIDIOC_QUERYCAP: ") + std::strerror(errno) + " (not a V4L2 device?)"};
  }
  NodeInfo info;
  info.driver = Text(cap.driver, sizeof(cap.driver));
  info.card = Text(cap.card, sizeof(cap.card));
  info.bus_info = Text(cap.bus_info, sizeof(cap.bus_info));
  info.device_caps =
      (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
  return info;
}

bool CanCapture(const NodeInfo& info) {
  return (info.device_caps & V4L2_CAP_VIDEO_CAPTURE) != 0 &&
         (info.device_caps & V4L2_CAP_STREAMING) != 0;
}

Expected<std::string> ResolveNode(const std::string& device) {
  const bool by_bus = device.rfind("bus:", 0) == 0;
  const bool by_card = device.rfind("card:", 0) == 0;
  if (!by_bus && !by_card) {
    std::error_code error;
    const std::filesystem::path resolved = std::filesystem::canonical(device, error);
    if (error) return Error{device + ": " + error.message()};
    return resolved.string();
  }
  const std::string wanted = device.substr(by_bus ? 4 : 5);
  std::string seen;
  for (const std::string& node : VideoNodes()) {
    const int fd = open(node.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) continue;
    auto info = QueryNode(fd);
    close(fd);
    if (!info || !CanCapture(*info)) continue;
    const std::string& field = by_bus ? info->bus_info : info->card;
    if (field == wanted) return node;
    seen += (seen.empty() ? "" : ", ") + node + " (" + field + ")";
  }
  return Error{"no V4L2 capture node with " + std::string(by_bus ? "bus info" : "card") + " '" +
               wanted + "'" + (seen.empty() ? " (no capture node found)" : "; found: " + seen)};
}

}  // namespace rigcal::capture::v4l2
