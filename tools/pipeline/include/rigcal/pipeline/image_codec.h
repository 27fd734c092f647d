// SPDX-License-Identifier: Apache-2.0
#pragma once
// Camera frames <-> image_t (RIGCAL_IMAGE_<camera>, lcmtypes/image_t.lcm): how `rigcal record`
// and `rigcal import` store images, and how a replay gets them back as the frames (CV_8UC1 grey)
// the VO takes.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/capture/frame.h"
#include "rigcal/image_t.hpp"
#include "rigcal/lcm/message_validation.h"

namespace rigcal::pipeline {

// How image_t.data holds the pixels: raw rows (no CPU, largest), PNG (lossless, ~2x smaller,
// slowest) or JPEG (lossy, smallest).
enum class ImageEncoding { kRaw, kPng, kJpeg };
const char* ToString(ImageEncoding encoding);  // "raw", "png", "jpeg"
std::optional<ImageEncoding> ParseImageEncoding(std::string_view text);

struct ImageEncodeOptions {
  ImageEncoding encoding = ImageEncoding::kRaw;
  int png_compression = 1;  // 0..9 (zlib level; 1 is fast and within ~5 % of 9 on camera images)
  int jpeg_quality = 90;    // 1..100
  // Success, or "<field>: <constraint>".
  Status Check() const;
};

// The image_t of a CV_8UC1 frame of camera `camera`: t_ns and trigger_seq from the frame, utime
// = `utime`, pixel_format "GREY", stride = width for raw images and 0 for PNG/JPEG. Errors: an
// image that is empty or not CV_8UC1, an encoder failure, invalid options.
Expected<image_t> FrameToImageMessage(const capture::Frame& frame, const std::string& camera,
                                      int64_t utime, const ImageEncodeOptions& options);

// FrameToImageMessage at utime = t_ns / 1000 for camera names[camera], checked and encoded for
// RIGCAL_IMAGE_<name> (EncodeMessage): the data of one log event.
Expected<std::vector<uint8_t>> EncodeImageEvent(const capture::Frame& frame,
                                                const lcm::CameraNames& names, int camera,
                                                const ImageEncodeOptions& options);

// The frame of a (checked, see image_message.h) image_t for camera index `camera`: t_ns and seq
// (trigger_seq) from the message, the pixels as a CV_8UC1 image of width x height: raw GREY,
// "Y16 " (the high byte), "YUYV" (the luma), "RGB3"/"BGR3" (converted to grey), or a PNG/JPEG
// file decoded to grey. Errors name the camera and say what is wrong: an unsupported pixel
// format, data that does not decode, a decoded size other than width x height.
Expected<capture::Frame> FrameFromImage(const image_t& msg, int camera);

}  // namespace rigcal::pipeline
