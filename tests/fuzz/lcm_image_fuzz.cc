// SPDX-License-Identifier: Apache-2.0
// Fuzz target `lcm_image`: image_t from any bytes (lcm_decode_fuzz.h): sizes that lie (size
// against data, stride x height, width against the pixel format), then FrameFromImage, the
// replay's conversion to a grey frame, whose result is width x height when it succeeds.

#include "lcm_decode_fuzz.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/pipeline/image_codec.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  const char* channel = "RIGCAL_IMAGE_back";
  std::optional<image_t> msg = fuzz::DecodeAndCheck<image_t>(channel, fuzz::kFuzzNames, data, size);
  fuzz::DecodeAndCheck<image_t>(channel, {}, data, size);
  if (!msg) return 0;
  Expected<capture::Frame> frame = pipeline::FrameFromImage(*msg, 2);
  if (frame) {
    RIGCAL_FUZZ_EXPECT(frame->image.cols == msg->width && frame->image.rows == msg->height,
                       "a frame of width x height");
    RIGCAL_FUZZ_EXPECT(frame->image.type() == CV_8UC1, "a grey frame");
  } else {
    RIGCAL_FUZZ_EXPECT(!frame.error().empty(), "a refused image says why");
  }
  return 0;
}
