// SPDX-License-Identifier: Apache-2.0
#pragma once
// Frame: one image from one camera, the value every capture source produces.

#include <cstdint>
#include <opencv2/core.hpp>

namespace rigcal::capture {

struct Frame {
  int camera = 0;    // index in the rig: 0 = master
  int64_t t_ns = 0;  // capture time, CLOCK_MONOTONIC of the capturing host
  int64_t seq = -1;  // trigger pulse / frame sequence number, -1 when unknown
  cv::Mat image;     // CV_8UC1 grey
  // No image, a progress mark: the source holds nothing more of this camera stamped before
  // t_ns. A lossless replay sends it for a camera that has no frame in the log while the
  // others go on, so that the merge of the cameras' poses does not wait for it.
  bool progress_mark = false;
};

}  // namespace rigcal::capture
