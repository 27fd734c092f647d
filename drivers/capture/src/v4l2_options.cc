// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/v4l2_options.h"

namespace rigcal::capture {

const std::vector<PixelFormat>& DefaultFormatPreference() {
  static const std::vector<PixelFormat> preference = {PixelFormat::kGrey, PixelFormat::kY16,
                                                      PixelFormat::kY10,  PixelFormat::kYuyv,
                                                      PixelFormat::kNv12, PixelFormat::kMjpeg};
  return preference;
}

Status V4l2Options::Check() const {
  if (device.empty())
    return Error{"device: missing (a /dev/video path, bus:<info> or card:<name>)"};
  if (width <= 0 || height <= 0) return Error{"size: width and height must be > 0"};
  for (PixelFormat f : formats) {
    if (f == PixelFormat::kBgr24 || f == PixelFormat::kRgb24) {
      return Error{"pixel_formats: RGB formats are not read from V4L2"};
    }
  }
  if (!(frame_rate_hz >= 0.0 && frame_rate_hz <= 10000.0)) {
    return Error{"frame_rate_hz: must be in [0, 10000]"};
  }
  if (buffers < 2 || buffers > 32) return Error{"buffers: must be in [2, 32]"};
  if (exposure_us && !(*exposure_us > 0.0 && *exposure_us <= 1e7)) {
    return Error{"exposure_us: must be in (0, 1e7]"};
  }
  if (!(readout_us >= 0.0 && readout_us <= 1e6)) return Error{"readout_us: must be in [0, 1e6]"};
  if (!(reconnect_max_backoff_s > 0.0 && reconnect_max_backoff_s <= 3600.0)) {
    return Error{"reconnect_max_backoff_s: must be in (0, 3600]"};
  }
  if (!(frame_timeout_s >= 0.0 && frame_timeout_s <= 3600.0)) {
    return Error{"frame_timeout_s: must be in [0, 3600]"};
  }
  return Status::Ok();
}

}  // namespace rigcal::capture
