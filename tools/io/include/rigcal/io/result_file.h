// SPDX-License-Identifier: Apache-2.0
#pragma once
// Reading a calibration result back: the result YAML every command writes with --out
// (ResultToYaml, rig_files.h) or the JSON of --json (ResultToJson, result_json.h), for tools that
// show a finished calibration (`rigcal report`).

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::io {

// Reads a result file; JSON when its first non-blank character is '{', else the result YAML.
// Filled: master, pairs_selected (YAML), and per slave name, estimate (q, C, scale), scales (with
// σ), rot_std_deg, pos_std, axis_offset_std (NaN when unknown: .nan / null), motions (YAML: by
// cause; JSON: used, and the rejected count as residual_outlier), motion and scale models,
// termination, state and message. Everything else keeps its default (observability, glitches).
// Errors name the path and the line (YAML) or byte offset (JSON) and the field: unreadable file,
// syntax, a missing or malformed field, an unknown state / termination / model, no slaves.
Expected<RigCalibration> ReadResultFile(const std::string& path);

// The unit of the result's C as its provenance states it: the text of `provenance.units.C`
// (ResultUnits of provenance.h: "m: ..." for metres, "master odometry unit: ..." otherwise);
// empty when the file carries no provenance (written before result schema 2). Errors: unreadable
// file, syntax.
Expected<std::string> ReadResultDistanceUnit(const std::string& path);

}  // namespace rigcal::io
