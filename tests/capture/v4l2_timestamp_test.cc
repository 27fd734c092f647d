// SPDX-License-Identifier: Apache-2.0
// Capture times of V4L2 buffers from their stamps and flags (no device needed).

#include "rigcal/capture/v4l2_timestamp.h"

#include <gtest/gtest.h>
#include <linux/videodev2.h>

namespace rigcal::capture {
namespace {

constexpr int64_t kDequeue = 99'000'000'000;

BufferStamp Stamp(uint32_t flags) {
  BufferStamp stamp;
  stamp.tv_sec = 12;
  stamp.tv_usec = 345'678;
  stamp.flags = flags;
  return stamp;
}

TEST(V4l2Timestamp, StartOfExposureIsKept) {
  const CaptureTime t =
      BufferCaptureTime(Stamp(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_SOE),
                        kDequeue, 5'000'000, 7'000'000);
  EXPECT_EQ(t.t_ns, 12'345'678'000);
  EXPECT_FALSE(t.end_of_frame);
  EXPECT_FALSE(t.from_dequeue);
}

TEST(V4l2Timestamp, EndOfFrameMovesBackByExposureAndReadout) {
  const CaptureTime t =
      BufferCaptureTime(Stamp(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | V4L2_BUF_FLAG_TSTAMP_SRC_EOF),
                        kDequeue, 5'000'000, 7'000'000);
  EXPECT_TRUE(t.end_of_frame);
  EXPECT_EQ(t.shifted_back_ns, 12'000'000);
  EXPECT_EQ(t.t_ns, 12'345'678'000 - 12'000'000);
  // Unknown exposure and readout: the stamp as it is.
  const CaptureTime raw =
      BufferCaptureTime(Stamp(V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC), kDequeue, 0, 0);
  EXPECT_EQ(raw.t_ns, 12'345'678'000);
  EXPECT_TRUE(raw.end_of_frame);
}

TEST(V4l2Timestamp, CopiedOrUnknownStampsUseTheDequeueTime) {
  for (uint32_t clock : {V4L2_BUF_FLAG_TIMESTAMP_UNKNOWN, V4L2_BUF_FLAG_TIMESTAMP_COPY}) {
    const CaptureTime t = BufferCaptureTime(Stamp(clock), kDequeue, 5'000'000, 0);
    EXPECT_EQ(t.t_ns, kDequeue);
    EXPECT_TRUE(t.from_dequeue);
  }
}

TEST(V4l2Timestamp, MonotonicNowIncreases) {
  const int64_t a = MonotonicNowNs();
  const int64_t b = MonotonicNowNs();
  EXPECT_GT(a, 0);
  EXPECT_GE(b, a);
}

}  // namespace
}  // namespace rigcal::capture
