// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/config_check.h"

#include <sstream>

#include "rigcal/capture/libcamera_device.h"
#include "rigcal/capture/v4l2_device.h"
#include "rigcal/trigger/serial_port.h"
#include "rigcal/trigger/trigger_hello.h"
#include "rigcal/trigger/trigger_link.h"

namespace rigcal::pipeline {
namespace {

constexpr int kHelloTimeoutMs = 2000;

// "<path>:<line>: cameras[<i>] '<name>'.device" (the line when the config was read from a file).
std::string DeviceKey(const io::RigConfig& config, size_t i) {
  const std::string key = "cameras[" + std::to_string(i) + "]";
  return config.Where(key + ".device") + key + " '" + config.cameras[i].name + "'.device";
}

void CheckV4l2(const io::RigConfig& config, bool open, ConfigCheck* check) {
  for (size_t i = 0; i < config.v4l2_devices.size(); ++i) {
    const capture::V4l2Options& o = config.v4l2_devices[i];
    std::ostringstream line;
    line << "camera '" << config.cameras[i].name << "': v4l2 " << o.device << " " << o.width << "x"
         << o.height;
    if (o.frame_rate_hz > 0) line << " at " << o.frame_rate_hz << " Hz";
    if (open) {
      auto device = capture::V4l2Device::Open(config.cameras[i].name, static_cast<int>(i), o);
      if (!device) {
        check->problems.push_back(DeviceKey(config, i) + ": " + device.error());
        continue;
      }
      const capture::V4l2Negotiated& n = (*device)->negotiated();
      line << " -> " << n.node << " (" << n.card << ", " << n.bus_info << ") "
           << capture::FourccText(n.fourcc) << " " << n.layout.width << "x" << n.layout.height
           << " at " << (*device)->frame_rate_hz() << " Hz";
    }
    check->plan.push_back(line.str());
  }
}

void CheckLibcamera(const io::RigConfig& config, bool open, ConfigCheck* check) {
  for (size_t i = 0; i < config.libcamera_devices.size(); ++i) {
    const capture::LibcameraOptions& o = config.libcamera_devices[i];
    std::ostringstream line;
    line << "camera '" << config.cameras[i].name << "': libcamera " << o.camera << " " << o.width
         << "x" << o.height << " (" << o.role << ")";
    if (open) {
      auto device = capture::LibcameraDevice::Open(config.cameras[i].name, static_cast<int>(i), o);
      if (!device) {
        check->problems.push_back(DeviceKey(config, i) + ": " + device.error());
        continue;
      }
      line << " -> " << (*device)->camera_id() << " " << (*device)->configuration();
    }
    check->plan.push_back(line.str());
  }
}

void CheckTrigger(const io::RigConfig& config, bool open, ConfigCheck* check) {
  if (!config.trigger) return;
  const trigger::LiveTriggerOptions& t = *config.trigger;
  std::ostringstream line;
  line << "trigger generator on " << t.port << " at " << t.baud << " baud: " << t.settings.rate_hz
       << " Hz, " << t.settings.lines.size() << " line(s)";
  if (open) {
    auto port = trigger::SerialPort::Open(t.port, t.baud);
    if (!port) {
      check->problems.push_back(config.Where("trigger.port") + "trigger.port: " + port.error());
      return;
    }
    trigger::TriggerLink link(std::move(*port));
    auto hello = trigger::QueryTriggerHello(&link, kHelloTimeoutMs);
    if (!hello) {
      check->problems.push_back(config.Where("trigger.port") + "trigger.port: " + t.port + ": " +
                                hello.error());
      return;
    }
    line << "; Hello: firmware " << hello->hello.firmware_version << ", "
         << static_cast<int>(hello->hello.max_lines) << " lines, round trip "
         << static_cast<double>(hello->round_trip_ns) * 1e-6 << " ms";
  }
  check->plan.push_back(line.str());
}

void PlanOutputs(const io::RigConfig& config, ConfigCheck* check) {
  std::ostringstream line;
  line << "master '" << config.cameras.front().name << "', " << config.cameras.size()
       << " cameras; sets matched "
       << (config.online.sync.match_by_trigger_seq ? "by trigger pulse" : "by time");
  check->plan.push_back(line.str());
  std::ostringstream out;
  out << "RIGCAL_EXTRINSICS at " << config.publish.extrinsics_rate_hz << " Hz, RIGCAL_STATUS at "
      << config.publish.status_rate_hz << " Hz; state ";
  if (config.state.path.empty()) {
    out << "not saved (no state.path; --state)";
  } else {
    out << config.state.path << " every " << config.state.save_interval_s << " s";
  }
  check->plan.push_back(out.str());
}

}  // namespace

ConfigCheck CheckRigConfig(const io::RigConfig& config, bool open_devices) {
  ConfigCheck check;
  if (config.simulated_source) check.plan.push_back("source: the simulated rig");
  if (!config.image_folders.empty()) check.plan.push_back("source: image folders");
  if (!config.simulated_source && config.image_folders.empty() && config.v4l2_devices.empty() &&
      config.libcamera_devices.empty()) {
    check.problems.push_back(config.path +
                             ": source: missing (rigcal run needs simulated, image_folders, "
                             "v4l2 or libcamera)");
  }
  CheckV4l2(config, open_devices, &check);
  CheckLibcamera(config, open_devices, &check);
  CheckTrigger(config, open_devices, &check);
  PlanOutputs(config, &check);
  return check;
}

}  // namespace rigcal::pipeline
