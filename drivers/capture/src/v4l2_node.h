// SPDX-License-Identifier: Apache-2.0
#pragma once
// Finding and querying V4L2 device nodes (private to the V4L2 source).

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::capture::v4l2 {

// ioctl retried on EINTR; returns its result (-1 with errno set on failure).
int Ioctl(int fd, unsigned long request, void* arg);

struct NodeInfo {
  std::string driver;
  std::string card;
  std::string bus_info;
  uint32_t device_caps = 0;  // device_caps when the driver gives them, else capabilities
};

// VIDIOC_QUERYCAP of an open node.
Expected<NodeInfo> QueryNode(int fd);
// Capture by the single-planar API with streaming I/O.
bool CanCapture(const NodeInfo& info);

// The node a V4l2Options::device names: a path (links resolved), "bus:<bus_info>" or
// "card:<card>" (first capture node among /dev/video* with that QUERYCAP field). Error when
// nothing matches, listing what was found.
Expected<std::string> ResolveNode(const std::string& device);

}  // namespace rigcal::capture::v4l2
