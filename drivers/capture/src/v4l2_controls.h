// SPDX-License-Identifier: Apache-2.0
#pragma once
// Setting a V4L2 node's controls from V4l2Options (private to the V4L2 source).

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/capture/v4l2_options.h"

namespace rigcal::capture::v4l2 {

struct Control {
  uint32_t id = 0;
  std::string name;  // as the driver names it
  int64_t minimum = 0;
  int64_t maximum = 0;
};

// A control name in the config's form: lower case, runs of non-alphanumerics as one '_'
// ("Trigger Mode" -> "trigger_mode").
std::string ControlKey(const std::string& name);

// The node's controls by ControlKey (VIDIOC_QUERYCTRL with V4L2_CTRL_FLAG_NEXT_CTRL; disabled
// controls and control classes left out).
std::map<std::string, Control> ListControls(int fd);

// Sets `value`; Error naming the control when it is out of range or the driver refuses it.
Status SetControl(int fd, const Control& control, int64_t value);
// Reads a control's value.
Expected<int64_t> GetControl(int fd, uint32_t id);

// Applies exposure, gain, external trigger and the named controls of `options`. Returns the
// exposure in ns the camera now has (0 when unknown). Errors name the option and the control.
Expected<int64_t> ApplyControls(int fd, const V4l2Options& options);

}  // namespace rigcal::capture::v4l2
