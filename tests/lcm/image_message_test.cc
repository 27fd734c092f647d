// SPDX-License-Identifier: Apache-2.0
// image_t: round trips of raw and compressed images and every rule of its CheckMessage.
#include "rigcal/lcm/image_message.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm::lcm_test {
namespace {

TEST(ImageMessage, RoundTrip) {
  const image_t back = ExpectRoundTrip(ImageChannel("back"), MakeImageMsg());
  EXPECT_EQ(back.pixel_format, "GREY");
  EXPECT_EQ(back.size, 15);
  ASSERT_EQ(back.data.size(), 15u);
  EXPECT_EQ(back.data[14], 17 * 14);

  image_t jpeg = MakeImageMsg();
  jpeg.encoding = image_t::ENCODING_JPEG;
  jpeg.pixel_format = "MJPG";
  jpeg.stride = 0;
  jpeg.data = {0xff, 0xd8, 0xff, 0xd9};
  jpeg.size = 4;
  EXPECT_EQ(ExpectRoundTrip(ImageChannel("back"), jpeg).data[1], 0xd8);
}

TEST(ImageMessage, RejectsBadSize) {
  MessageValidator validator(kNames);
  const image_t image = MakeImageMsg();
  std::vector<uint8_t> buffer = Encode("I", image);
  ASSERT_EQ(GetInt32(buffer, ImageSizeOffset(image)), 15);
  PutInt32(&buffer, ImageSizeOffset(image), -15);
  ExpectRejected<image_t>(&validator, "I", buffer, RejectCause::kBadSize,
                          {"image_t.size", "negative length"});
  // Consistent on the wire, inconsistent with width/height/stride.
  image_t short_image = image;
  short_image.data.pop_back();
  short_image.size = 14;
  ExpectRejected<image_t>(&validator, "I", RawEncode(short_image), RejectCause::kBadSize,
                          {"image_t.size", "14 bytes but stride x height = 15"});
  image_t narrow = image;
  narrow.pixel_format = "BGR3";
  ExpectRejected<image_t>(&validator, "I", RawEncode(narrow), RejectCause::kBadSize,
                          {"image_t.stride", "less than width 4 x 3 bytes"});
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kBadSize), 3);

  image_t image_mismatch = MakeImageMsg();
  image_mismatch.size = 16;
  std::optional<Rejection> rejection = CheckMessage("I", kNames, &image_mismatch);
  ASSERT_TRUE(rejection.has_value());
  EXPECT_EQ(rejection->cause, RejectCause::kBadSize);
}

TEST(ImageMessage, RejectsUnknownCamera) {
  MessageValidator validator(kNames);
  image_t image = MakeImageMsg();
  image.camera = "roof";
  ExpectRejected<image_t>(&validator, "I", RawEncode(image), RejectCause::kUnknownCamera,
                          {"image_t.camera"});
}

TEST(ImageMessage, RejectsOutOfRange) {
  MessageValidator validator(kNames);
  image_t image = MakeImageMsg();
  image.encoding = 9;
  ExpectRejected<image_t>(&validator, "I", RawEncode(image), RejectCause::kOutOfRange,
                          {"image_t.encoding"});
  image = MakeImageMsg();
  image.pixel_format = "GRAY8";
  ExpectRejected<image_t>(&validator, "I", RawEncode(image), RejectCause::kOutOfRange,
                          {"image_t.pixel_format"});
}

}  // namespace
}  // namespace rigcal::lcm::lcm_test
