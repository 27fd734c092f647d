// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/pixel_format.h"

#include <linux/videodev2.h>

#include <algorithm>
#include <cctype>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

namespace rigcal::capture {
namespace {

int BytesPerPixel(PixelFormat format) {
  switch (format) {
    case PixelFormat::kY10:
    case PixelFormat::kY16:
    case PixelFormat::kYuyv:
      return 2;
    case PixelFormat::kBgr24:
    case PixelFormat::kRgb24:
      return 3;
    default:
      return 1;
  }
}

std::string Describe(const ImageLayout& layout) {
  return std::string(ToString(layout.format)) + " " + std::to_string(layout.width) + "x" +
         std::to_string(layout.height) + " (" + std::to_string(layout.bytes_per_line) +
         " bytes per line)";
}

int Stride(const ImageLayout& layout) {
  return layout.bytes_per_line > 0 ? layout.bytes_per_line
                                   : layout.width * BytesPerPixel(layout.format);
}

}  // namespace

const char* ToString(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return "GREY";
    case PixelFormat::kY10:
      return "Y10";
    case PixelFormat::kY16:
      return "Y16";
    case PixelFormat::kYuyv:
      return "YUYV";
    case PixelFormat::kNv12:
      return "NV12";
    case PixelFormat::kMjpeg:
      return "MJPEG";
    case PixelFormat::kBgr24:
      return "BGR24";
    case PixelFormat::kRgb24:
      return "RGB24";
  }
  return "?";
}

std::optional<PixelFormat> ParsePixelFormat(const std::string& name) {
  std::string upper = name;
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  if (upper == "MJPG") return PixelFormat::kMjpeg;
  for (PixelFormat f :
       {PixelFormat::kGrey, PixelFormat::kY10, PixelFormat::kY16, PixelFormat::kYuyv,
        PixelFormat::kNv12, PixelFormat::kMjpeg, PixelFormat::kBgr24, PixelFormat::kRgb24}) {
    if (upper == ToString(f)) return f;
  }
  return std::nullopt;
}

uint32_t V4l2Fourcc(PixelFormat format) {
  switch (format) {
    case PixelFormat::kGrey:
      return V4L2_PIX_FMT_GREY;
    case PixelFormat::kY10:
      return V4L2_PIX_FMT_Y10;
    case PixelFormat::kY16:
      return V4L2_PIX_FMT_Y16;
    case PixelFormat::kYuyv:
      return V4L2_PIX_FMT_YUYV;
    case PixelFormat::kNv12:
      return V4L2_PIX_FMT_NV12;
    case PixelFormat::kMjpeg:
      return V4L2_PIX_FMT_MJPEG;
    case PixelFormat::kBgr24:
      return V4L2_PIX_FMT_BGR24;
    case PixelFormat::kRgb24:
      return V4L2_PIX_FMT_RGB24;
  }
  return 0;
}

std::optional<PixelFormat> FromV4l2Fourcc(uint32_t fourcc) {
  if (fourcc == V4L2_PIX_FMT_JPEG) return PixelFormat::kMjpeg;
  for (PixelFormat f :
       {PixelFormat::kGrey, PixelFormat::kY10, PixelFormat::kY16, PixelFormat::kYuyv,
        PixelFormat::kNv12, PixelFormat::kMjpeg, PixelFormat::kBgr24, PixelFormat::kRgb24}) {
    if (V4l2Fourcc(f) == fourcc) return f;
  }
  return std::nullopt;
}

std::string FourccText(uint32_t fourcc) {
  std::string text;
  for (int i = 0; i < 4; ++i) {
    const char c = static_cast<char>((fourcc >> (8 * i)) & 0xff);
    text += std::isprint(static_cast<unsigned char>(c)) ? c : '?';
  }
  while (!text.empty() && text.back() == ' ') text.pop_back();
  return text;
}

size_t MinimumBytes(const ImageLayout& layout) {
  if (layout.format == PixelFormat::kMjpeg) return 1;
  const size_t luma = static_cast<size_t>(Stride(layout)) * static_cast<size_t>(layout.height);
  // NV12's chroma plane is not read; only the luma plane must be there.
  return luma;
}

Expected<cv::Mat> ConvertToGrey(const ImageLayout& layout, const uint8_t* data, size_t size) {
  const int w = layout.width;
  const int h = layout.height;
  if (w <= 0 || h <= 0 || layout.bytes_per_line < 0 ||
      (layout.bytes_per_line > 0 && layout.format != PixelFormat::kMjpeg &&
       layout.bytes_per_line < w * BytesPerPixel(layout.format))) {
    return Error{"invalid image layout " + Describe(layout)};
  }
  if (data == nullptr || size < MinimumBytes(layout)) {
    return Error{Describe(layout) + ": buffer holds " + std::to_string(size) + " bytes, needs " +
                 std::to_string(MinimumBytes(layout))};
  }
  const size_t stride = static_cast<size_t>(Stride(layout));
  cv::Mat grey(h, w, CV_8UC1);
  switch (layout.format) {
    case PixelFormat::kGrey:
    case PixelFormat::kNv12:
      for (int y = 0; y < h; ++y) {
        std::copy_n(data + y * stride, w, grey.ptr<uint8_t>(y));
      }
      break;
    case PixelFormat::kY10:
    case PixelFormat::kY16: {
      const int shift = layout.format == PixelFormat::kY10 ? 2 : 8;
      for (int y = 0; y < h; ++y) {
        const uint8_t* row = data + y * stride;
        uint8_t* out = grey.ptr<uint8_t>(y);
        for (int x = 0; x < w; ++x) {
          const unsigned value = row[2 * x] | (static_cast<unsigned>(row[2 * x + 1]) << 8);
          out[x] = static_cast<uint8_t>(std::min(255u, value >> shift));
        }
      }
      break;
    }
    case PixelFormat::kYuyv:
      for (int y = 0; y < h; ++y) {
        const uint8_t* row = data + y * stride;
        uint8_t* out = grey.ptr<uint8_t>(y);
        for (int x = 0; x < w; ++x) out[x] = row[2 * x];
      }
      break;
    case PixelFormat::kBgr24:
    case PixelFormat::kRgb24: {
      const cv::Mat colour(h, w, CV_8UC3, const_cast<uint8_t*>(data), stride);
      cv::cvtColor(colour, grey,
                   layout.format == PixelFormat::kBgr24 ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY);
      break;
    }
    case PixelFormat::kMjpeg: {
      const cv::Mat bytes(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
      cv::Mat decoded;
      try {
        decoded = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
      } catch (const cv::Exception& e) {
        return Error{"MJPEG: the JPEG does not decode: " + std::string(e.what())};
      }
      if (decoded.empty()) return Error{"MJPEG: the JPEG does not decode"};
      if (decoded.cols != w || decoded.rows != h) {
        return Error{"MJPEG: decoded " + std::to_string(decoded.cols) + "x" +
                     std::to_string(decoded.rows) + ", the format says " + std::to_string(w) + "x" +
                     std::to_string(h)};
      }
      return decoded;
    }
  }
  return grey;
}

}  // namespace rigcal::capture
