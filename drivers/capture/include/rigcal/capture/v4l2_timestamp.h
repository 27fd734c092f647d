// SPDX-License-Identifier: Apache-2.0
#pragma once
// The capture time of a dequeued V4L2 buffer in CLOCK_MONOTONIC nanoseconds, from its
// timestamp and flags (V4L2_BUF_FLAG_TIMESTAMP_MASK, V4L2_BUF_FLAG_TSTAMP_SRC_MASK). Pure, so
// it is unit-tested without a device.
//  - MONOTONIC stamps are CLOCK_MONOTONIC already. Start-of-exposure stamps (TSTAMP_SRC_SOE)
//    are kept. End-of-frame stamps (TSTAMP_SRC_EOF, the default) are moved back by the
//    exposure and the sensor readout when they are known, so that every camera is stamped at
//    the start of its exposure.
//  - UNKNOWN and COPY stamps (a loopback device copies its writer's stamp) are not a capture
//    clock: the time of the dequeue is used instead (the host's CLOCK_MONOTONIC then, minus
//    nothing), and `from_dequeue` says so.

#include <cstdint>

namespace rigcal::capture {

struct BufferStamp {
  int64_t tv_sec = 0;
  int64_t tv_usec = 0;
  uint32_t flags = 0;  // v4l2_buffer.flags
};

struct CaptureTime {
  int64_t t_ns = 0;
  bool from_dequeue = false;    // the driver's stamp was not CLOCK_MONOTONIC
  bool end_of_frame = false;    // the driver stamped the end of the frame
  int64_t shifted_back_ns = 0;  // subtracted from an end-of-frame stamp
};

// `dequeue_ns`: CLOCK_MONOTONIC at DQBUF. `exposure_ns`, `readout_ns`: >= 0, 0 when unknown.
CaptureTime BufferCaptureTime(const BufferStamp& stamp, int64_t dequeue_ns, int64_t exposure_ns,
                              int64_t readout_ns);

// CLOCK_MONOTONIC now, nanoseconds.
int64_t MonotonicNowNs();

}  // namespace rigcal::capture
