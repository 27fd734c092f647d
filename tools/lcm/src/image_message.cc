// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/image_message.h"

#include <algorithm>
#include <string>

#include "message_checker.h"
#include "message_codec.h"

namespace rigcal::lcm {
namespace {

using internal::Checker;
using internal::LayoutWalk;

// Bytes per pixel of the raw pixel formats this project writes; 0 when unknown.
int BytesPerPixel(const std::string& fourcc) {
  if (fourcc == "GREY") return 1;
  if (fourcc == "Y16 " || fourcc == "YUYV") return 2;
  if (fourcc == "RGB3" || fourcc == "BGR3") return 3;
  return 0;
}

// The fields of image_t.lcm up to the length of data.
void WalkImageLayout(LayoutWalk* walk) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Fixed("t_ns", 8);
  walk->String("camera");
  walk->Fixed("trigger_seq", 8);
  walk->Fixed("width", 4);
  walk->Fixed("height", 4);
  walk->Fixed("stride", 4);
  walk->String("pixel_format");
  walk->Fixed("encoding", 1);
  walk->Count("size", 1);
}

// The rules of image_t (image_message.h) but the version.
void CheckImage(const CameraNames& names, image_t* msg, Checker* check) {
  check->Count("size", msg->size, msg->data.size(), "data");
  if (!check->ok()) return;
  check->CameraName("camera", msg->camera, names, 0, "the rig's cameras");
  check->AtLeast<int64_t>("utime", msg->utime, 0);
  check->AtLeast<int64_t>("t_ns", msg->t_ns, 0);
  check->AtLeast<int64_t>("trigger_seq", msg->trigger_seq, -1);
  check->AtLeast<int32_t>("width", msg->width, 0);
  check->AtLeast<int32_t>("height", msg->height, 0);
  check->AtLeast<int32_t>("stride", msg->stride, 0);
  check->InRange<int8_t>("encoding", msg->encoding, image_t::ENCODING_RAW, image_t::ENCODING_PNG);
  check->Text("pixel_format", msg->pixel_format);
  if (check->ok() && msg->pixel_format.size() != 4) {
    check->Fail(RejectCause::kOutOfRange, "pixel_format",
                "'" + msg->pixel_format + "' is not a 4-character fourcc");
  }
  if (!check->ok()) return;
  if (msg->encoding == image_t::ENCODING_RAW) {
    const int bytes_per_pixel = std::max(1, BytesPerPixel(msg->pixel_format));
    const int64_t min_stride = int64_t{msg->width} * bytes_per_pixel;
    const int64_t expected_size = int64_t{msg->stride} * msg->height;
    if (msg->stride < min_stride) {
      check->Fail(RejectCause::kBadSize, "stride",
                  std::to_string(msg->stride) + " bytes is less than width " +
                      std::to_string(msg->width) + " x " + std::to_string(bytes_per_pixel) +
                      " bytes of " + msg->pixel_format);
    } else if (msg->size != expected_size) {
      check->Fail(RejectCause::kBadSize, "size",
                  std::to_string(msg->size) +
                      " bytes but stride x height = " + std::to_string(expected_size));
    }
  } else if (msg->size == 0) {
    check->Fail(RejectCause::kBadSize, "size", "empty compressed image");
  }
}

}  // namespace

template <>
struct internal::MessageTraits<image_t> {
  static constexpr char kTypeName[] = "image_t";
  static constexpr auto WalkLayout = &WalkImageLayout;
  static constexpr auto CheckContent = &CheckImage;
};

template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&, image_t*);
template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                      image_t);
template Expected<image_t> MessageValidator::Decode(std::string_view, const void*, int64_t);

}  // namespace rigcal::lcm
