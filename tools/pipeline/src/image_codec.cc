// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/image_codec.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"

namespace rigcal::pipeline {

const char* ToString(ImageEncoding encoding) {
  switch (encoding) {
    case ImageEncoding::kRaw:
      return "raw";
    case ImageEncoding::kPng:
      return "png";
    case ImageEncoding::kJpeg:
      return "jpeg";
  }
  return "?";
}

std::optional<ImageEncoding> ParseImageEncoding(std::string_view text) {
  for (ImageEncoding e : {ImageEncoding::kRaw, ImageEncoding::kPng, ImageEncoding::kJpeg}) {
    if (text == ToString(e)) return e;
  }
  return std::nullopt;
}

Status ImageEncodeOptions::Check() const {
  if (png_compression < 0 || png_compression > 9) return Error{"png_compression: must be 0..9"};
  if (jpeg_quality < 1 || jpeg_quality > 100) return Error{"jpeg_quality: must be 1..100"};
  return Status::Ok();
}

Expected<image_t> FrameToImageMessage(const capture::Frame& frame, const std::string& camera,
                                      int64_t utime, const ImageEncodeOptions& options) {
  if (const Status status = options.Check(); !status.ok()) {
    return Error{"ImageEncodeOptions: " + status.message()};
  }
  const cv::Mat& image = frame.image;
  if (image.empty() || image.type() != CV_8UC1) {
    return Error{"camera '" + camera + "': frame at t_ns " + std::to_string(frame.t_ns) +
                 " is not an 8-bit grey image"};
  }
  image_t msg;
  msg.version = image_t::VERSION;
  msg.utime = utime;
  msg.t_ns = frame.t_ns;
  msg.camera = camera;
  msg.trigger_seq = frame.seq;
  msg.width = image.cols;
  msg.height = image.rows;
  msg.pixel_format = "GREY";
  if (options.encoding == ImageEncoding::kRaw) {
    msg.encoding = image_t::ENCODING_RAW;
    msg.stride = image.cols;
    msg.data.resize(image.total());
    for (int row = 0; row < image.rows; ++row) {
      const uint8_t* src = image.ptr<uint8_t>(row);
      std::copy(src, src + image.cols, msg.data.begin() + static_cast<ptrdiff_t>(row) * image.cols);
    }
  } else {
    const bool png = options.encoding == ImageEncoding::kPng;
    msg.encoding = png ? image_t::ENCODING_PNG : image_t::ENCODING_JPEG;
    msg.stride = 0;
    const std::vector<int> params =
        png ? std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, options.png_compression}
            : std::vector<int>{cv::IMWRITE_JPEG_QUALITY, options.jpeg_quality};
    bool ok = false;
    try {
      ok = cv::imencode(png ? ".png" : ".jpg", image, msg.data, params);
    } catch (const cv::Exception& e) {
      return Error{"camera '" + camera + "': " + ToString(options.encoding) +
                   " encoding failed: " + e.what()};
    }
    if (!ok || msg.data.empty()) {
      return Error{"camera '" + camera + "': " + ToString(options.encoding) + " encoding failed"};
    }
  }
  msg.size = static_cast<int32_t>(msg.data.size());
  return msg;
}

Expected<std::vector<uint8_t>> EncodeImageEvent(const capture::Frame& frame,
                                                const lcm::CameraNames& names, int camera,
                                                const ImageEncodeOptions& options) {
  const std::string& name = names.at(static_cast<size_t>(camera));
  Expected<image_t> msg = FrameToImageMessage(frame, name, frame.t_ns / 1000, options);
  if (!msg) return msg.status();
  return lcm::EncodeMessage(lcm::ImageChannel(name), names, std::move(*msg));
}

namespace {

// The pixels of `msg` as grey (FrameFromImage); `who` names the image in errors.
Expected<cv::Mat> GreyPixels(const image_t& msg, const std::string& who) {
  if (msg.encoding != image_t::ENCODING_RAW) {
    cv::Mat decoded;
    try {
      decoded = cv::imdecode(msg.data, cv::IMREAD_GRAYSCALE);
    } catch (const cv::Exception& e) {
      return Error{who + ": cannot decode its " + std::to_string(msg.size) + " bytes: " + e.what()};
    }
    if (decoded.empty()) {
      return Error{who + ": its " + std::to_string(msg.size) + " bytes do not decode as " +
                   (msg.encoding == image_t::ENCODING_PNG ? "PNG" : "JPEG")};
    }
    if (decoded.cols != msg.width || decoded.rows != msg.height) {
      return Error{who + ": decodes to " + std::to_string(decoded.cols) + "x" +
                   std::to_string(decoded.rows) + ", the message says " +
                   std::to_string(msg.width) + "x" + std::to_string(msg.height)};
    }
    return decoded;
  }
  // Raw rows of `stride` bytes; image_message.h's checks guarantee size = stride x height.
  if (static_cast<int64_t>(msg.data.size()) < int64_t{msg.stride} * msg.height) {
    return Error{who + ": " + std::to_string(msg.data.size()) +
                 " bytes, fewer than stride x height"};
  }
  auto* data = const_cast<uint8_t*>(msg.data.data());  // wrapped read-only, then copied
  const auto stride = static_cast<size_t>(msg.stride);
  cv::Mat grey;
  if (msg.pixel_format == "GREY") {
    cv::Mat(msg.height, msg.width, CV_8UC1, data, stride).copyTo(grey);
  } else if (msg.pixel_format == "Y16 ") {
    cv::Mat(msg.height, msg.width, CV_16UC1, data, stride).convertTo(grey, CV_8U, 1.0 / 256.0);
  } else if (msg.pixel_format == "YUYV") {
    cv::cvtColor(cv::Mat(msg.height, msg.width, CV_8UC2, data, stride), grey,
                 cv::COLOR_YUV2GRAY_YUYV);
  } else if (msg.pixel_format == "RGB3" || msg.pixel_format == "BGR3") {
    cv::cvtColor(cv::Mat(msg.height, msg.width, CV_8UC3, data, stride), grey,
                 msg.pixel_format == "RGB3" ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  } else {
    return Error{who + ": raw pixel format '" + msg.pixel_format +
                 "' is not supported (GREY, Y16 , YUYV, RGB3, BGR3)"};
  }
  return grey;
}

}  // namespace

Expected<capture::Frame> FrameFromImage(const image_t& msg, int camera) {
  const std::string who = "camera '" + msg.camera + "' image at t_ns " + std::to_string(msg.t_ns);
  // A 0-pixel image passes image_t's checks; it gave an empty frame, not width x height (found by
  // the lcm_image fuzz target).
  if (msg.width <= 0 || msg.height <= 0) {
    return Error{who + ": no pixels (" + std::to_string(msg.width) + " x " +
                 std::to_string(msg.height) + ")"};
  }
  Expected<cv::Mat> grey = GreyPixels(msg, who);
  if (!grey) return grey.status();
  capture::Frame frame;
  frame.camera = camera;
  frame.t_ns = msg.t_ns;
  frame.seq = msg.trigger_seq;
  frame.image = std::move(*grey);
  return frame;
}

}  // namespace rigcal::pipeline
