// SPDX-License-Identifier: Apache-2.0
#pragma once
// The cameras and serial ports of this computer, for `rigcal devices` and a config's check:
// every V4L2 capture node (driver, card, bus, the stable /dev/v4l/by-id and by-path names that
// point at it, pixel formats and frame sizes), the cameras libcamera sees, and the serial ports a
// trigger generator could sit on (USB CDC / USB-UART adapters and on-board UARTs, with their
// /dev/serial/by-id and by-path names). Nothing is captured: nodes are opened, queried and
// closed.

#include <cstdint>
#include <string>
#include <vector>

namespace rigcal::capture {

struct V4l2FormatInfo {
  std::string fourcc;       // "GREY", "YUYV", ...
  std::string description;  // the driver's
  // "752x480" per discrete size, or "16x16..1920x1080 step 2x2" for a range.
  std::vector<std::string> sizes;
};

struct V4l2NodeInfo {
  std::string node;  // /dev/videoN
  std::string driver;
  std::string card;
  std::string bus_info;
  std::vector<std::string> stable_paths;  // /dev/v4l/by-id/..., /dev/v4l/by-path/...
  std::vector<V4l2FormatInfo> formats;
};

struct SerialPortInfo {
  std::string node;                       // /dev/ttyUSB0, /dev/ttyACM0, /dev/ttyAMA0, ...
  std::string driver;                     // from sysfs, empty when unknown
  std::vector<std::string> stable_paths;  // /dev/serial/by-id/..., /dev/serial/by-path/...
};

struct DeviceList {
  std::vector<V4l2NodeInfo> v4l2;          // capture nodes only (no metadata / output nodes)
  std::vector<std::string> v4l2_problems;  // "/dev/video3: Permission denied"
  bool libcamera_built_in = false;
  std::vector<std::string> libcamera;  // "<id> (<model>)"
  std::string libcamera_problem;       // why the list could not be had; empty when fine
  std::vector<SerialPortInfo> serial;
};

// Looks under `dev` (normally /dev) and `sys` (normally /sys; the drivers of serial ports).
DeviceList ListDevices(const std::string& dev = "/dev", const std::string& sys = "/sys");

}  // namespace rigcal::capture
