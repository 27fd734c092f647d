// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/v4l2_timestamp.h"

#include <linux/videodev2.h>

#include <ctime>

namespace rigcal::capture {

CaptureTime BufferCaptureTime(const BufferStamp& stamp, int64_t dequeue_ns, int64_t exposure_ns,
                              int64_t readout_ns) {
  CaptureTime time;
  const uint32_t clock = stamp.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK;
  if (clock != V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    time.t_ns = dequeue_ns;
    time.from_dequeue = true;
    return time;
  }
  time.t_ns = stamp.tv_sec * 1'000'000'000 + stamp.tv_usec * 1'000;
  time.end_of_frame = (stamp.flags & V4L2_BUF_FLAG_TSTAMP_SRC_MASK) == V4L2_BUF_FLAG_TSTAMP_SRC_EOF;
  if (time.end_of_frame) {
    time.shifted_back_ns = (exposure_ns > 0 ? exposure_ns : 0) + (readout_ns > 0 ? readout_ns : 0);
    time.t_ns -= time.shifted_back_ns;
  }
  return time;
}

int64_t MonotonicNowNs() {
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000'000 + now.tv_nsec;
}

}  // namespace rigcal::capture
