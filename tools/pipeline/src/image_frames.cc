#include "rigcal/pipeline/image_frames.h"

#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace rigcal::tools {
namespace {

// A view of the raw pixels of a checked message (size = stride x height).
cv::Mat RawView(const image_t& image, int type) {
  return cv::Mat(image.height, image.width, type, const_cast<uint8_t*>(image.data.data()),
                 static_cast<size_t>(image.stride));
}

Expected<cv::Mat> GreyOfRaw(const image_t& image) {
  const std::string& f = image.pixel_format;
  cv::Mat grey;
  if (f == "GREY") {
    RawView(image, CV_8UC1).copyTo(grey);
  } else if (f == "Y16 ") {
    RawView(image, CV_16UC1).convertTo(grey, CV_8U, 1.0 / 256.0);
  } else if (f == "YUYV") {
    cv::cvtColor(RawView(image, CV_8UC2), grey, cv::COLOR_YUV2GRAY_YUYV);
  } else if (f == "RGB3") {
    cv::cvtColor(RawView(image, CV_8UC3), grey, cv::COLOR_RGB2GRAY);
  } else if (f == "BGR3") {
    cv::cvtColor(RawView(image, CV_8UC3), grey, cv::COLOR_BGR2GRAY);
  } else {
    return Error{"raw pixel format '" + f + "' is not supported (GREY, Y16, YUYV, RGB3, BGR3)"};
  }
  return grey;
}

}  // namespace

Expected<drivers::Frame> FrameFromImage(const image_t& image, int camera) {
  drivers::Frame frame;
  frame.camera = camera;
  frame.t_ns = image.t_ns;
  frame.seq = image.trigger_seq;
  if (image.encoding == image_t::ENCODING_RAW) {
    auto grey = GreyOfRaw(image);
    if (!grey) return Error{"camera '" + image.camera + "': " + grey.error()};
    frame.image = std::move(*grey);
  } else {
    const cv::Mat bytes(1, static_cast<int>(image.data.size()), CV_8UC1,
                        const_cast<uint8_t*>(image.data.data()));
    frame.image = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
    if (frame.image.empty()) {
      return Error{"camera '" + image.camera + "': image at " + std::to_string(image.t_ns) +
                   " ns: the " + (image.encoding == image_t::ENCODING_PNG ? "PNG" : "JPEG") +
                   " data cannot be decoded"};
    }
  }
  return frame;
}

image_t ImageOfFrame(const drivers::Frame& frame, const std::string& name) {
  image_t image{};
  image.version = image_t::VERSION;
  image.utime = frame.t_ns / 1000;
  image.t_ns = frame.t_ns;
  image.camera = name;
  image.trigger_seq = frame.seq;
  image.width = frame.image.cols;
  image.height = frame.image.rows;
  image.stride = frame.image.cols;
  image.pixel_format = "GREY";
  image.encoding = image_t::ENCODING_RAW;
  image.data.resize(static_cast<size_t>(image.stride) * static_cast<size_t>(image.height));
  for (int r = 0; r < image.height; ++r) {
    std::memcpy(image.data.data() + static_cast<size_t>(r) * image.stride, frame.image.ptr(r),
                static_cast<size_t>(image.width));
  }
  image.size = static_cast<int32_t>(image.data.size());
  return image;
}

}  // namespace rigcal::tools
