// SPDX-License-Identifier: Apache-2.0
#pragma once
// The writer side of a v4l2loopback device (scripts/vm/guest-init.sh loads two: /dev/video20 and
// /dev/video21): S_FMT on the OUTPUT type, then one write() per frame, which the driver stamps
// (CLOCK_MONOTONIC, at the write) and hands to the capture readers. Frames are converted to the
// device's pixel format beforehand (Pack), so a write costs only the copy into the driver.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rigcal/capture/pixel_format.h"

namespace rigcal::capture {

class LoopbackWriter {
 public:
  // Opens `node` and sets its output format (GREY or YUYV, width x height); errors go to
  // error() (empty when the device is ready).
  LoopbackWriter(const std::string& node, PixelFormat format, int width, int height);
  ~LoopbackWriter();
  LoopbackWriter(const LoopbackWriter&) = delete;
  LoopbackWriter& operator=(const LoopbackWriter&) = delete;

  const std::string& error() const { return error_; }
  // A grey CV_8UC1 image of the device's size in the device's format (YUYV: neutral chroma).
  std::vector<uint8_t> Pack(const cv::Mat& grey) const;
  // One frame; false (and error()) when the driver took less than the whole frame.
  bool Write(const std::vector<uint8_t>& bytes);

 private:
  int fd_ = -1;
  PixelFormat format_;
  int width_;
  int height_;
  std::string node_;
  std::string error_;
};

}  // namespace rigcal::capture
