// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/device_list.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <map>
#include <regex>

#include "rigcal/capture/libcamera_device.h"
#include "v4l2_node.h"

namespace rigcal::capture {
namespace {

namespace fs = std::filesystem;

std::string FourccString(uint32_t fourcc) {
  std::string text(4, ' ');
  for (int i = 0; i < 4; ++i) text[i] = static_cast<char>((fourcc >> (8 * i)) & 0xff);
  return text;
}

// Every symlink in the folders `dirs` (under `dev`) by the canonical node it points at.
std::map<std::string, std::vector<std::string>> LinksByTarget(const std::vector<fs::path>& dirs) {
  std::map<std::string, std::vector<std::string>> links;
  for (const fs::path& dir : dirs) {
    std::error_code ec;
    for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
      std::error_code target_ec;
      const fs::path target = fs::canonical(entry.path(), target_ec);
      if (!target_ec) links[target.string()].push_back(entry.path().string());
    }
  }
  for (auto& [target, paths] : links) std::sort(paths.begin(), paths.end());
  return links;
}

// Nodes in `dev` whose names match `pattern`, sorted by name then number.
std::vector<std::string> Nodes(const std::string& dev, const std::regex& pattern) {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dev, ec)) {
    if (std::regex_match(entry.path().filename().string(), pattern)) {
      nodes.push_back(entry.path().string());
    }
  }
  std::sort(nodes.begin(), nodes.end(), [](const std::string& a, const std::string& b) {
    return a.size() != b.size() ? a.size() < b.size() : a < b;
  });
  return nodes;
}

std::vector<std::string> FrameSizes(int fd, uint32_t fourcc) {
  std::vector<std::string> sizes;
  v4l2_frmsizeenum size{};
  size.pixel_format = fourcc;
  for (size.index = 0; v4l2::Ioctl(fd, VIDIOC_ENUM_FRAMESIZES, &size) == 0; ++size.index) {
    if (size.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
      sizes.push_back(std::to_string(size.discrete.width) + "x" +
                      std::to_string(size.discrete.height));
      continue;
    }
    const v4l2_frmsize_stepwise& s = size.stepwise;
    sizes.push_back(std::to_string(s.min_width) + "x" + std::to_string(s.min_height) + ".." +
                    std::to_string(s.max_width) + "x" + std::to_string(s.max_height) + " step " +
                    std::to_string(s.step_width) + "x" + std::to_string(s.step_height));
    break;  // a range is one entry
  }
  return sizes;
}

std::vector<V4l2FormatInfo> Formats(int fd) {
  std::vector<V4l2FormatInfo> formats;
  v4l2_fmtdesc desc{};
  desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  for (desc.index = 0; v4l2::Ioctl(fd, VIDIOC_ENUM_FMT, &desc) == 0; ++desc.index) {
    V4l2FormatInfo format;
    format.fourcc = FourccString(desc.pixelformat);
    format.description = reinterpret_cast<const char*>(desc.description);
    format.sizes = FrameSizes(fd, desc.pixelformat);
    formats.push_back(format);
  }
  return formats;
}

void ListV4l2(const std::string& dev, DeviceList* list) {
  const auto links = LinksByTarget({fs::path(dev) / "v4l/by-id", fs::path(dev) / "v4l/by-path"});
  for (const std::string& node : Nodes(dev, std::regex("video[0-9]+"))) {
    const int fd = ::open(node.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      list->v4l2_problems.push_back(node + ": " + std::strerror(errno));
      continue;
    }
    auto info = v4l2::QueryNode(fd);
    if (info && v4l2::CanCapture(*info)) {
      V4l2NodeInfo entry{node, info->driver, info->card, info->bus_info, {}, Formats(fd)};
      std::error_code ec;
      const auto found = links.find(fs::canonical(node, ec).string());
      if (found != links.end()) entry.stable_paths = found->second;
      list->v4l2.push_back(entry);
    } else if (!info) {
      list->v4l2_problems.push_back(node + ": " + info.error());
    }
    ::close(fd);
  }
}

void ListSerial(const std::string& dev, const std::string& sys, DeviceList* list) {
  const auto links =
      LinksByTarget({fs::path(dev) / "serial/by-id", fs::path(dev) / "serial/by-path"});
  const std::regex pattern("tty(USB|ACM|AMA|S|THS|mxc|LP)[0-9]+");
  for (const std::string& node : Nodes(dev, pattern)) {
    const std::string name = fs::path(node).filename().string();
    // On-board 8250 UARTs are listed (ttyS0..31) whether present or not: only those with a
    // device behind them in sysfs other than the legacy placeholder platform count.
    std::error_code ec;
    const fs::path driver =
        fs::read_symlink(fs::path(sys) / "class/tty" / name / "device/driver", ec);
    const std::string driver_name = ec ? "" : driver.filename().string();
    if (name.rfind("ttyS", 0) == 0 && (driver_name.empty() || driver_name == "serial8250")) {
      continue;
    }
    SerialPortInfo port{node, driver_name, {}};
    const auto found = links.find(fs::canonical(node, ec).string());
    if (found != links.end()) port.stable_paths = found->second;
    list->serial.push_back(port);
  }
}

}  // namespace

DeviceList ListDevices(const std::string& dev, const std::string& sys) {
  DeviceList list;
  ListV4l2(dev, &list);
  list.libcamera_built_in = LibcameraBuiltIn();
  if (list.libcamera_built_in) {
    auto cameras = ListLibcameraCameras();
    if (cameras) {
      list.libcamera = *cameras;
    } else {
      list.libcamera_problem = cameras.error();
    }
  }
  ListSerial(dev, sys, &list);
  return list;
}

}  // namespace rigcal::capture
