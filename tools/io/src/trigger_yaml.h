// SPDX-License-Identifier: Apache-2.0
#pragma once
// The hardware trigger of a rig config (docs/config.md "Hardware trigger"): the top-level
// `trigger:` section (the generator on a serial port) and each triggered camera's `trigger:`
// entry (its line and exposure). Errors read "<path>:<line>: <field>: <what>".
//
//   trigger: {port: /dev/ttyACM0, baud: 115200, rate_hz: 20, heartbeat_ms: 100,
//             uart_wire: true, tolerance_ms: 5, command_timeout_ms: 1000}
//   cameras[i].trigger: {line: 0, phase_us: 0, width_us: 1000, exposure_us: 4000,
//                        stamp: start_of_exposure | exposure_centre | end_of_frame,
//                        readout_us: 0, exposure_input: none | active_high | active_low}

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <optional>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/trigger/live_trigger_timeline.h"
#include "yaml_fields.h"

namespace rigcal::io {

// A camera's `trigger:` entry as written; the source decides the defaults (rig_config.cc).
struct CameraTriggerConfig {
  int line = 0;                              // [0, 8), required
  std::optional<int64_t> width_us;           // pulse width; default min(1000, period / 2)
  int64_t phase_us = 0;                      // exposure centre - tick
  std::optional<int64_t> exposure_us;        // v4l2: capture.exposure_us instead
  std::optional<trigger::FrameStamp> stamp;  // v4l2: from the buffer flags instead
  int64_t readout_us = 0;                    // sensor readout, for stamp end_of_frame
  // The camera's exposure output wired to the line's capture input (docs/firmware.md): frames
  // then get the measured exposure centre.
  trigger_protocol::ExposureInput exposure_input = trigger_protocol::ExposureInput::kNone;
};

// The top-level `trigger:` map into `options` (port, baud, rate_hz, heartbeat_ms, uart_wire,
// tolerance_ms, command_timeout_ms); its lines come from the cameras.
std::optional<Error> ParseTriggerSection(const FieldReader& r, const YAML::Node& node,
                                         trigger::LiveTriggerOptions* options);

// A camera's `trigger:` map; `field` names it in errors ("cam1.trigger").
Expected<CameraTriggerConfig> ParseCameraTrigger(const FieldReader& r, const YAML::Node& node,
                                                 const std::string& field);

// The trigger of a rig config, once its cameras and source are read: fills config->trigger (its
// lines from the cameras' entries) and config->camera_triggers, and sets
// sync.match_by_trigger_seq when every camera is triggered (unless `sync:` sets it, or the
// cameras run free with estimator.time_offset). Where a frame is stamped relative to the
// exposure centre, by source: v4l2 start of exposure (v4l2_timestamp.h; the exposure is
// capture.exposure_us), libcamera start of exposure (SensorTimestamp), image_folders and
// simulated the exposure centre; `stamp` overrides it except for v4l2. `entries[i]`: the YAML
// entry of camera i (index order); `source_type` "" without a source.
std::optional<Error> ReadRigTrigger(const FieldReader& r, const YAML::Node& root,
                                    const std::vector<YAML::Node>& entries,
                                    const std::string& source_type, RigConfig* config);

}  // namespace rigcal::io
