// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/libcamera_device.h"

namespace rigcal::capture {

Status LibcameraOptions::Check() const {
  if (width <= 0 || height <= 0) return Error{"size: width and height must be > 0"};
  if (role != "video" && role != "viewfinder" && role != "still" && role != "raw") {
    return Error{"role: '" + role + "' is not one of video, viewfinder, still, raw"};
  }
  for (PixelFormat f : formats) {
    if (f == PixelFormat::kY10 || f == PixelFormat::kY16) {
      return Error{std::string("pixel_formats: ") + ToString(f) + " is not read from libcamera"};
    }
  }
  if (buffers < 1 || buffers > 32) return Error{"buffers: must be in [1, 32]"};
  if (!(reconnect_max_backoff_s > 0.0 && reconnect_max_backoff_s <= 3600.0)) {
    return Error{"reconnect_max_backoff_s: must be in (0, 3600]"};
  }
  return Status::Ok();
}

}  // namespace rigcal::capture
