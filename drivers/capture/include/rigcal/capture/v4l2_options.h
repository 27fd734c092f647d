// SPDX-License-Identifier: Apache-2.0
#pragma once
// The settings of one V4L2 capture device (the `v4l2` source of a rig config: the camera's
// `device` and its `capture:` options over the source's defaults; docs/config.md).

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/capture/pixel_format.h"

namespace rigcal::capture {

struct V4l2Options {
  // Which device: a node path ("/dev/video0", a /dev/v4l/by-id or by-path link), or
  // "bus:<bus_info>" (VIDIOC_QUERYCAP bus_info, e.g. "bus:platform:vivid-001",
  // "bus:usb-0000:00:14.0-1") or "card:<card name>" of a capture node. Resolved again on every
  // reconnection.
  std::string device;
  int width = 0;  // pixels, > 0 (the camera model's resolution); the driver must accept it
  int height = 0;
  // Preferred pixel formats, first supported one wins; empty: GREY, Y16, Y10, YUYV, NV12, MJPEG.
  std::vector<PixelFormat> formats;
  double frame_rate_hz = 0.0;  // requested rate (VIDIOC_S_PARM); 0: the driver's
  int buffers = 4;             // mmap buffers, [2, 32]
  // Manual exposure (V4L2_CID_EXPOSURE_AUTO manual + EXPOSURE_ABSOLUTE) and gain
  // (V4L2_CID_GAIN, else ANALOGUE_GAIN); unset: left as the driver has them.
  std::optional<double> exposure_us;
  std::optional<int64_t> gain;
  // External trigger: the driver's control named "Trigger Mode" (or the first control whose
  // name contains "trigger") is set to 1; an error when the driver has none.
  bool external_trigger = false;
  // Further controls by name (lower case, non-alphanumerics as '_': "power_line_frequency").
  std::map<std::string, int64_t> controls;
  // Sensor readout time (first to last row), microseconds >= 0: with the exposure it moves
  // end-of-frame stamps back to the start of exposure (see v4l2_timestamp.h).
  double readout_us = 0.0;
  // Device loss (ENODEV, EIO, a vanished node): reopen with backoff from 0.1 s doubling up to
  // this (s, > 0). When false the device fails instead (the pipeline marks the camera dead).
  bool reconnect = true;
  double reconnect_max_backoff_s = 2.0;
  // No frame for this long (s) while streaming counts as device loss; 0: wait forever (an
  // externally triggered camera may pause).
  double frame_timeout_s = 0.0;

  // Success or "<field>: <constraint>".
  Status Check() const;
};

// The default format preference (GREY first: no conversion).
const std::vector<PixelFormat>& DefaultFormatPreference();

}  // namespace rigcal::capture
