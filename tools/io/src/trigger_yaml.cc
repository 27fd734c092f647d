// SPDX-License-Identifier: Apache-2.0
#include "trigger_yaml.h"

#include <cmath>

namespace rigcal::io {
namespace {

// An optional integer at node[key] in [lo, hi] into *out.
std::optional<Error> OptionalInteger(const FieldReader& r, const YAML::Node& node,
                                     const std::string& prefix, const char* key, int64_t lo,
                                     int64_t hi, int64_t* out) {
  const YAML::Node n = node[key];
  if (!n) return std::nullopt;
  auto v = r.Integer64(n, prefix + key);
  if (!v) return Error{v.error()};
  if (*v < lo || *v > hi) {
    return r.Fail(n, prefix + key,
                  "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  *out = *v;
  return std::nullopt;
}

}  // namespace

std::optional<Error> ParseTriggerSection(const FieldReader& r, const YAML::Node& node,
                                         trigger::LiveTriggerOptions* options) {
  if (auto e = r.CheckKeys(node, "trigger.",
                           {"port", "baud", "rate_hz", "heartbeat_ms", "uart_wire", "tolerance_ms",
                            "command_timeout_ms"})) {
    return e;
  }
  if (!node["port"]) {
    return r.Fail(node, "trigger.port", "missing (the generator's serial device, /dev/ttyACM0)");
  }
  auto port = r.String(node["port"], "trigger.port");
  if (!port) return Error{port.error()};
  options->port = *port;
  int64_t value = options->baud;
  if (auto e = OptionalInteger(r, node, "trigger.", "baud", 1200, 4'000'000, &value)) return e;
  options->baud = static_cast<int>(value);
  if (const YAML::Node n = node["rate_hz"]) {
    auto v = r.Number(n, "trigger.rate_hz");
    if (!v) return Error{v.error()};
    if (!(*v >= 0.1 && *v <= 400)) return r.Fail(n, "trigger.rate_hz", "must be in [0.1, 400]");
    options->settings.rate_hz = *v;
  }
  value = options->settings.heartbeat_ms;
  if (auto e = OptionalInteger(r, node, "trigger.", "heartbeat_ms", 0, 10000, &value)) return e;
  if (value != 0 && value < 10) {
    return r.Fail(node["heartbeat_ms"], "trigger.heartbeat_ms",
                  "must be 0 (off) or in [10, 10000]");
  }
  options->settings.heartbeat_ms = static_cast<int>(value);
  if (const YAML::Node n = node["uart_wire"]) {
    auto v = r.Bool(n, "trigger.uart_wire");
    if (!v) return Error{v.error()};
    options->uart_wire = *v;
  }
  if (const YAML::Node n = node["tolerance_ms"]) {
    auto v = r.Number(n, "trigger.tolerance_ms");
    if (!v) return Error{v.error()};
    if (!(*v > 0 && *v <= 1000)) return r.Fail(n, "trigger.tolerance_ms", "must be in (0, 1000]");
    options->matcher.tolerance_ns = std::llround(*v * 1e6);
  }
  value = options->command_timeout_ms;
  if (auto e = OptionalInteger(r, node, "trigger.", "command_timeout_ms", 10, 60000, &value)) {
    return e;
  }
  options->command_timeout_ms = static_cast<int>(value);
  return std::nullopt;
}

Expected<CameraTriggerConfig> ParseCameraTrigger(const FieldReader& r, const YAML::Node& node,
                                                 const std::string& field) {
  const std::string p = field + ".";
  if (auto e = r.CheckKeys(node, p,
                           {"line", "phase_us", "width_us", "exposure_us", "stamp", "readout_us",
                            "exposure_input"})) {
    return *e;
  }
  CameraTriggerConfig c;
  if (!node["line"]) return r.Fail(node, p + "line", "missing (the generator's line, 0 to 7)");
  int64_t line = 0;
  if (auto e = OptionalInteger(r, node, p, "line", 0, 7, &line)) return *e;
  c.line = static_cast<int>(line);
  if (auto e = OptionalInteger(r, node, p, "phase_us", -1'000'000, 1'000'000, &c.phase_us)) {
    return *e;
  }
  if (node["width_us"]) {
    int64_t width = 0;
    if (auto e = OptionalInteger(r, node, p, "width_us", trigger_protocol::kMinWidthUs, 10'000'000,
                                 &width)) {
      return *e;
    }
    c.width_us = width;
  }
  if (node["exposure_us"]) {
    int64_t exposure = 0;
    if (auto e = OptionalInteger(r, node, p, "exposure_us", 0, 1'000'000, &exposure)) return *e;
    c.exposure_us = exposure;
  }
  if (auto e = OptionalInteger(r, node, p, "readout_us", 0, 1'000'000, &c.readout_us)) return *e;
  if (const YAML::Node n = node["stamp"]) {
    auto text = r.String(n, p + "stamp");
    if (!text) return Error{text.error()};
    c.stamp = trigger::FrameStampFromString(*text);
    if (!c.stamp) {
      return r.Fail(
          n, p + "stamp",
          "'" + *text + "' is not one of start_of_exposure, exposure_centre, end_of_frame");
    }
  }
  if (const YAML::Node n = node["exposure_input"]) {
    auto text = r.String(n, p + "exposure_input");
    if (!text) return Error{text.error()};
    using trigger_protocol::ExposureInput;
    if (*text == "none") {
      c.exposure_input = ExposureInput::kNone;
    } else if (*text == "active_high") {
      c.exposure_input = ExposureInput::kActiveHigh;
    } else if (*text == "active_low") {
      c.exposure_input = ExposureInput::kActiveLow;
    } else {
      return r.Fail(n, p + "exposure_input",
                    "'" + *text + "' is not one of none, active_high, active_low");
    }
  }
  if (node["readout_us"] && c.stamp != trigger::FrameStamp::kEndOfFrame) {
    return r.Fail(node["readout_us"], p + "readout_us", "only with stamp: end_of_frame");
  }
  return c;
}

namespace {

// Every camera's `trigger:` entry; one without the top-level section is an error.
Expected<std::vector<std::optional<CameraTriggerConfig>>> ReadCameraTriggers(
    const FieldReader& r, const YAML::Node& section, const std::vector<YAML::Node>& entries,
    const RigConfig& config) {
  std::vector<std::optional<CameraTriggerConfig>> cameras(config.cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    const YAML::Node node = entries[i].IsMap() ? entries[i]["trigger"] : YAML::Node();
    if (!node) continue;
    const std::string field = config.cameras[i].name + ".trigger";
    if (!section) {
      return r.Fail(node, field, "needs the top-level `trigger:` section (the generator's port)");
    }
    auto parsed = ParseCameraTrigger(r, node, field);
    if (!parsed) return Error{parsed.error()};
    cameras[i] = *parsed;
  }
  return cameras;
}

// The generator's section against the cameras and a simulated source.
std::optional<Error> CheckTriggerWithSource(const FieldReader& r, const YAML::Node& section,
                                            size_t triggered,
                                            const trigger::LiveTriggerOptions& options,
                                            const RigConfig& config) {
  if (triggered == 0) {
    return r.Fail(section, "trigger", "no camera has a `trigger:` entry (its line)");
  }
  if (config.simulated_source && config.simulated_source->trigger.enabled) {
    return r.Fail(section, "trigger",
                  "not with source.trigger (the simulated generator): give one of them");
  }
  if (config.simulated_source &&
      std::abs(config.simulated_source->frame_rate_hz - options.settings.rate_hz) > 1e-9) {
    return r.Fail(section["rate_hz"] ? section["rate_hz"] : section, "trigger.rate_hz",
                  "must be the simulated source's frame_rate_hz (the rig's frame k is pulse k)");
  }
  return std::nullopt;
}

// A camera's exposure [us] for its line: a v4l2 camera's is its capture.exposure_us.
Expected<int64_t> CameraExposureUs(const FieldReader& r, const YAML::Node& node,
                                   const std::string& p, const CameraTriggerConfig& c, bool v4l2,
                                   std::optional<double> v4l2_exposure_us) {
  if (!v4l2) return c.exposure_us.value_or(0);
  // The V4L2 source sets the exposure and moves end-of-frame stamps back by it.
  if (c.exposure_us) {
    return r.Fail(node["exposure_us"], p + "exposure_us",
                  "for a v4l2 camera give capture.exposure_us (the camera's exposure "
                  "control, which also moves end-of-frame stamps back to the exposure start)");
  }
  if (c.stamp) {
    return r.Fail(node["stamp"], p + "stamp",
                  "a v4l2 camera's stamps follow its buffer flags (start of exposure)");
  }
  if (!v4l2_exposure_us) {
    return r.Fail(node, p + "exposure_us",
                  "a triggered v4l2 camera needs capture.exposure_us (the generator centres "
                  "its pulses on the exposure)");
  }
  return std::llround(*v4l2_exposure_us);
}

// The generator line of a camera, checked against the trigger period.
Expected<trigger::TriggerLineSettings> CameraLine(const FieldReader& r, const YAML::Node& node,
                                                  const std::string& p,
                                                  const CameraTriggerConfig& c, int64_t exposure_us,
                                                  int64_t period_us) {
  trigger::TriggerLineSettings line;
  line.line = c.line;
  line.width_us = c.width_us.value_or(std::min<int64_t>(1000, period_us / 2));
  line.phase_offset_us = c.phase_us;
  line.exposure_us = exposure_us;
  line.exposure_input = c.exposure_input;
  if (line.width_us >= period_us) {
    return r.Fail(node["width_us"] ? node["width_us"] : node, p + "width_us",
                  "must be below the trigger period " + std::to_string(period_us) + " us");
  }
  if (std::abs(line.phase_offset_us) + exposure_us / 2 >= period_us) {
    return r.Fail(node, p + "phase_us",
                  "|phase_us| + exposure / 2 must be below the trigger period " +
                      std::to_string(period_us) + " us");
  }
  return line;
}

// Adds a camera's line to the generator's, or checks it against the camera sharing it.
std::optional<Error> AddLine(const FieldReader& r, const YAML::Node& node, const std::string& p,
                             const trigger::TriggerLineSettings& line,
                             trigger::TriggerSettings* settings) {
  for (const trigger::TriggerLineSettings& other : settings->lines) {
    if (other.line != line.line) continue;
    if (other.width_us != line.width_us || other.phase_offset_us != line.phase_offset_us ||
        other.exposure_us != line.exposure_us || other.exposure_input != line.exposure_input) {
      return r.Fail(node, p + "line",
                    "line " + std::to_string(line.line) +
                        " is shared with another camera whose width, phase, exposure or "
                        "exposure input differ");
    }
    return std::nullopt;
  }
  settings->lines.push_back(line);
  return std::nullopt;
}

}  // namespace

std::optional<Error> ReadRigTrigger(const FieldReader& r, const YAML::Node& root,
                                    const std::vector<YAML::Node>& entries,
                                    const std::string& source_type, RigConfig* config) {
  const YAML::Node section = root["trigger"];
  const size_t n = config->cameras.size();
  auto cameras = ReadCameraTriggers(r, section, entries, *config);
  if (!cameras) return Error{cameras.error()};
  if (!section) return std::nullopt;
  size_t triggered = 0;
  for (const auto& camera : *cameras) triggered += camera ? 1 : 0;
  trigger::LiveTriggerOptions options;
  if (auto e = ParseTriggerSection(r, section, &options)) return e;
  if (auto e = CheckTriggerWithSource(r, section, triggered, options, *config)) return e;
  const auto period_us = static_cast<int64_t>(1e6 / options.settings.rate_hz);
  const bool v4l2 = source_type == "v4l2";
  const bool start_of_exposure = v4l2 || source_type == "libcamera";
  config->camera_triggers.assign(n, std::nullopt);
  for (size_t i = 0; i < n; ++i) {
    if (!(*cameras)[i]) continue;
    const CameraTriggerConfig& c = *(*cameras)[i];
    const YAML::Node node = entries[i]["trigger"];
    const std::string p = config->cameras[i].name + ".trigger.";
    auto exposure_us = CameraExposureUs(r, node, p, c, v4l2,
                                        v4l2 ? config->v4l2_devices[i].exposure_us : std::nullopt);
    if (!exposure_us) return Error{exposure_us.error()};
    auto line = CameraLine(r, node, p, c, *exposure_us, period_us);
    if (!line) return Error{line.error()};
    if (auto e = AddLine(r, node, p, *line, &options.settings)) return e;
    const trigger::FrameStamp stamp =
        c.stamp.value_or(start_of_exposure ? trigger::FrameStamp::kStartOfExposure
                                           : trigger::FrameStamp::kExposureCentre);
    config->camera_triggers[i] = trigger::CameraTriggerSpec{
        c.line, c.phase_us * 1000, trigger::StampOffsetNs(stamp, *exposure_us, c.readout_us),
        c.exposure_input != trigger_protocol::ExposureInput::kNone};
  }
  if (Status s = options.Check(); !s.ok()) return r.Fail(section, "trigger", s.message());
  config->trigger = std::move(options);
  const YAML::Node sync_node = root["sync"];
  const bool given = sync_node && sync_node.IsMap() && sync_node["match_by_trigger_seq"];
  if (triggered == n && !given && !config->online.time_offset.enabled) {
    config->online.sync.match_by_trigger_seq = true;
  }
  return std::nullopt;
}

}  // namespace rigcal::io
