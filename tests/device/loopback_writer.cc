// SPDX-License-Identifier: Apache-2.0
#include "loopback_writer.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace rigcal::capture {

LoopbackWriter::LoopbackWriter(const std::string& node, PixelFormat format, int width, int height)
    : format_(format), width_(width), height_(height), node_(node) {
  fd_ = open(node.c_str(), O_RDWR);
  if (fd_ < 0) {
    error_ = node + ": " + std::strerror(errno);
    return;
  }
  const int bytes_per_pixel = format == PixelFormat::kYuyv ? 2 : 1;
  v4l2_format f{};
  f.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
  f.fmt.pix.width = width;
  f.fmt.pix.height = height;
  f.fmt.pix.pixelformat = V4l2Fourcc(format);
  f.fmt.pix.field = V4L2_FIELD_NONE;
  f.fmt.pix.bytesperline = width * bytes_per_pixel;
  f.fmt.pix.sizeimage = width * height * bytes_per_pixel;
  if (ioctl(fd_, VIDIOC_S_FMT, &f) != 0) {
    error_ = node + ": S_FMT: " + std::strerror(errno);
  } else if (f.fmt.pix.pixelformat != V4l2Fourcc(format) ||
             static_cast<int>(f.fmt.pix.width) != width ||
             static_cast<int>(f.fmt.pix.height) != height) {
    error_ = node + ": the driver changed the output format to " +
             FourccText(f.fmt.pix.pixelformat) + " " + std::to_string(f.fmt.pix.width) + "x" +
             std::to_string(f.fmt.pix.height);
  }
}

LoopbackWriter::~LoopbackWriter() {
  if (fd_ >= 0) close(fd_);
}

std::vector<uint8_t> LoopbackWriter::Pack(const cv::Mat& grey) const {
  if (format_ != PixelFormat::kYuyv) {
    std::vector<uint8_t> bytes(static_cast<size_t>(width_) * height_);
    for (int y = 0; y < height_; ++y) std::memcpy(&bytes[y * width_], grey.ptr(y), width_);
    return bytes;
  }
  std::vector<uint8_t> bytes(static_cast<size_t>(width_) * height_ * 2);
  for (int y = 0; y < height_; ++y) {
    const uint8_t* row = grey.ptr<uint8_t>(y);
    for (int x = 0; x < width_; ++x) {
      bytes[2 * (y * width_ + x)] = row[x];
      bytes[2 * (y * width_ + x) + 1] = 128;  // neutral chroma
    }
  }
  return bytes;
}

bool LoopbackWriter::Write(const std::vector<uint8_t>& bytes) {
  const ssize_t n = write(fd_, bytes.data(), bytes.size());
  if (n == static_cast<ssize_t>(bytes.size())) return true;
  error_ = node_ + ": write: " + (n < 0 ? std::strerror(errno) : std::to_string(n) + " bytes");
  return false;
}

}  // namespace rigcal::capture
