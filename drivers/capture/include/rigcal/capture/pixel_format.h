// SPDX-License-Identifier: Apache-2.0
#pragma once
// Pixel formats a capture device may deliver and their conversion to the CV_8UC1 grey image of
// a Frame. Pure functions of the buffer bytes (no device needed), so they are unit-tested on any
// machine. V4L2 fourccs and libcamera's DRM fourccs name the same layouts:
//   GREY  8-bit luma;                Y10  10-bit luma in the low bits of 16-bit little-endian
//   Y16   16-bit little-endian luma; YUYV packed 4:2:2 (Y0 U Y1 V), luma at even bytes;
//   NV12  luma plane then interleaved chroma (4:2:0); MJPEG one JPEG image per buffer;
//   BGR24 packed 8-bit B,G,R in memory (libcamera's RGB888), RGB24 R,G,B in memory (libcamera's
//   BGR888); both converted with BT.601 luma weights.

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "rigcal/base/status.h"

namespace rigcal::capture {

enum class PixelFormat { kGrey, kY10, kY16, kYuyv, kNv12, kMjpeg, kBgr24, kRgb24 };

// "GREY", "Y10", "Y16", "YUYV", "NV12", "MJPEG", "BGR24", "RGB24".
const char* ToString(PixelFormat format);
// The inverse of ToString (case-insensitive; "MJPG" is accepted too), or nullopt.
std::optional<PixelFormat> ParsePixelFormat(const std::string& name);
// The V4L2 fourcc of a format (V4L2_PIX_FMT_*), and the format of a V4L2 fourcc (nullopt for a
// layout rigcal does not convert).
uint32_t V4l2Fourcc(PixelFormat format);
std::optional<PixelFormat> FromV4l2Fourcc(uint32_t fourcc);
// A fourcc as its four characters ("YUYV"), for messages.
std::string FourccText(uint32_t fourcc);

// Where the image lies in a buffer: `width` x `height` pixels, rows `bytes_per_line` apart
// (0 = packed: width times the bytes per pixel). NV12's chroma plane follows the luma plane
// (height rows of bytes_per_line bytes) and is not read.
struct ImageLayout {
  PixelFormat format = PixelFormat::kGrey;
  int width = 0;
  int height = 0;
  int bytes_per_line = 0;
};

// The bytes a buffer of this layout must hold at least (MJPEG: 1, since JPEG sizes vary).
size_t MinimumBytes(const ImageLayout& layout);

// The grey image (CV_8UC1, width x height, owning its pixels) of `size` bytes at `data`.
// Y10 keeps the top 8 of its 10 bits, Y16 the high byte; MJPEG is decoded by OpenCV and must
// have the layout's size. Error (naming the format and the sizes) when the buffer is too short,
// the layout is invalid or a JPEG does not decode.
Expected<cv::Mat> ConvertToGrey(const ImageLayout& layout, const uint8_t* data, size_t size);

}  // namespace rigcal::capture
