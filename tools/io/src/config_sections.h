// SPDX-License-Identifier: Apache-2.0
#pragma once
// Parsers of the sections of a rig config file (docs/config.md). yaml-cpp stays inside
// tools/: each parser fills a plain options struct of its module. Errors read
// "<path>:<line>: <key>: <what is wrong>" (line is 1-based, from the node's mark).

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/calib/clock_offset_tracker.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::io {

// One entry of `cameras:` (name, model, resolution, intrinsics, distortion, scaramuzza fields).
// Keys owned by other parsers (nominal, truth, device) are skipped here; any other unknown key
// is an error.
Expected<camera::CameraSpec> ParseCameraSection(const YAML::Node& camera, const std::string& path);

// The `source:` section of type `simulated`. Fills every field of SimulatedRigSpec that the
// section owns; cameras and their true mounting are filled by the caller from `cameras:`.
Expected<sim::SimulatedRigSpec> ParseSimulatedSource(const YAML::Node& source,
                                                     const std::string& path);

// `estimator.time_offset` (cameras that run free): `auto` (every slave's clock offset
// estimated), a number of seconds (every slave's, given), or a map from slave names to `auto` or
// seconds (slaves not named: auto). Given offsets lie in [-86400, 86400] s. Unknown names, the
// master, other values and types are errors naming the field. `slave_names` in camera index
// order (the master excluded). Sets options->enabled and options->given_s.
Expected<ClockOffsetOptions> ParseTimeOffsetSection(const YAML::Node& node,
                                                    const std::vector<std::string>& slave_names,
                                                    const std::string& master,
                                                    const std::string& path);

}  // namespace rigcal::io
