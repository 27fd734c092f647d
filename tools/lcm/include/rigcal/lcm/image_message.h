// SPDX-License-Identifier: Apache-2.0
#pragma once
// image_t, one camera image on RIGCAL_IMAGE_<camera> (recording and replay): its checks.

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/image_t.hpp"
#include "rigcal/lcm/message_validation.h"

namespace rigcal::lcm {

// The rules of image_t (beyond message_validation.h), checked by CheckMessage, EncodeMessage and
// MessageValidator::Decode: size agrees with data, a known camera, utime and t_ns >= 0, trigger_seq
// >= -1, width, height and stride >= 0, a defined encoding, a 4-character pixel_format without NUL;
// a raw image has stride >= width x the bytes per pixel of its format (1 when unknown) and size =
// stride x height, a compressed one is not empty.
extern template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                                      image_t*);
extern template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                             image_t);
extern template Expected<image_t> MessageValidator::Decode(std::string_view, const void*, int64_t);

}  // namespace rigcal::lcm
