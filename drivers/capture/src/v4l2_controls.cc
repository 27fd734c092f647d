// SPDX-License-Identifier: Apache-2.0
#include "v4l2_controls.h"

#include <linux/videodev2.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "v4l2_node.h"

namespace rigcal::capture::v4l2 {
namespace {

std::optional<Control> ById(const std::map<std::string, Control>& controls, uint32_t id) {
  for (const auto& [key, control] : controls) {
    if (control.id == id) return control;
  }
  return std::nullopt;
}

}  // namespace

std::string ControlKey(const std::string& name) {
  std::string key;
  for (const char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      key += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } else if (!key.empty() && key.back() != '_') {
      key += '_';
    }
  }
  while (!key.empty() && key.back() == '_') key.pop_back();
  return key;
}

std::map<std::string, Control> ListControls(int fd) {
  std::map<std::string, Control> controls;
  v4l2_queryctrl query{};
  query.id = V4L2_CTRL_FLAG_NEXT_CTRL;
  while (Ioctl(fd, VIDIOC_QUERYCTRL, &query) == 0) {
    if ((query.flags & V4L2_CTRL_FLAG_DISABLED) == 0 && query.type != V4L2_CTRL_TYPE_CTRL_CLASS) {
      Control control;
      control.id = query.id;
      control.name = reinterpret_cast<const char*>(query.name);
      control.minimum = query.minimum;
      control.maximum = query.maximum;
      controls.emplace(ControlKey(control.name), control);
    }
    query.id |= V4L2_CTRL_FLAG_NEXT_CTRL;
  }
  return controls;
}

Status SetControl(int fd, const Control& control, int64_t value) {
  if (value < control.minimum || value > control.maximum) {
    return Error{"control '" + control.name + "': " + std::to_string(value) + " is outside [" +
                 std::to_string(control.minimum) + ", " + std::to_string(control.maximum) + "]"};
  }
  v4l2_control set{};
  set.id = control.id;
  set.value = static_cast<int32_t>(value);
  if (Ioctl(fd, VIDIOC_S_CTRL, &set) != 0) {
    return Error{"control '" + control.name + "': the driver refuses " + std::to_string(value) +
                 ": " + std::strerror(errno)};
  }
  return Status::Ok();
}

Expected<int64_t> GetControl(int fd, uint32_t id) {
  v4l2_control get{};
  get.id = id;
  if (Ioctl(fd, VIDIOC_G_CTRL, &get) != 0) {
    return Error{"VIDIOC_G_CTRL " + std::to_string(id) + ": " + std::strerror(errno)};
  }
  return static_cast<int64_t>(get.value);
}

Expected<int64_t> ApplyControls(int fd, const V4l2Options& options) {
  const std::map<std::string, Control> controls = ListControls(fd);
  int64_t exposure_ns = 0;
  if (options.exposure_us) {
    const auto automatic = ById(controls, V4L2_CID_EXPOSURE_AUTO);
    const auto absolute = ById(controls, V4L2_CID_EXPOSURE_ABSOLUTE);
    if (!absolute) return Error{"exposure_us: the driver has no Exposure (Absolute) control"};
    if (automatic) {
      if (Status s = SetControl(fd, *automatic, V4L2_EXPOSURE_MANUAL); !s.ok()) {
        return Error{"exposure_us: " + s.message()};
      }
    }
    const int64_t units = std::llround(*options.exposure_us / 100.0);  // 100 us units
    if (Status s = SetControl(fd, *absolute, units); !s.ok()) {
      return Error{"exposure_us: " + s.message()};
    }
    exposure_ns = units * 100'000;
  }
  if (options.gain) {
    if (const auto automatic = ById(controls, V4L2_CID_AUTOGAIN)) {
      if (Status s = SetControl(fd, *automatic, 0); !s.ok()) return Error{"gain: " + s.message()};
    }
    auto gain = ById(controls, V4L2_CID_GAIN);
    if (!gain) gain = ById(controls, V4L2_CID_ANALOGUE_GAIN);
    if (!gain) return Error{"gain: the driver has no Gain or Analogue Gain control"};
    if (Status s = SetControl(fd, *gain, *options.gain); !s.ok()) {
      return Error{"gain: " + s.message()};
    }
  }
  if (options.external_trigger) {
    std::optional<Control> trigger;
    const auto exact = controls.find("trigger_mode");
    if (exact != controls.end()) {
      trigger = exact->second;
    } else {
      for (const auto& [key, control] : controls) {
        if (key.find("trigger") != std::string::npos) {
          trigger = control;
          break;
        }
      }
    }
    if (!trigger) return Error{"external_trigger: the driver offers no trigger control"};
    if (Status s = SetControl(fd, *trigger, 1); !s.ok()) {
      return Error{"external_trigger: " + s.message()};
    }
  }
  for (const auto& [key, value] : options.controls) {
    const auto it = controls.find(key);
    if (it == controls.end()) {
      std::string known;
      for (const auto& entry : controls) known += (known.empty() ? "" : ", ") + entry.first;
      return Error{"controls." + key + ": the driver has no such control (it has: " + known + ")"};
    }
    if (Status s = SetControl(fd, it->second, value); !s.ok()) {
      return Error{"controls." + key + ": " + s.message()};
    }
  }
  return exposure_ns;
}

}  // namespace rigcal::capture::v4l2
