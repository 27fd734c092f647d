// SPDX-License-Identifier: Apache-2.0
#pragma once
// `--camchain FILE` of every command that has a result (solve, calib, replay): the Kalibr
// camchain of io/result_camchain.h with the rig config's intrinsics, in metres when the unit is
// known, else with the unit said in the file and a warning on the log.

#include <spdlog/logger.h>

#include <map>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/io/rig_config.h"

namespace rigcal::cli {

// The intrinsics of the config's cameras that have them, by name.
std::map<std::string, camera::CameraSpec> IntrinsicsOf(const io::RigConfig& config);

// Writes the camchain; `metres_per_unit`: 1 when the result's C are metres, NaN when unknown.
Status WriteResultCamchain(const std::string& path, const RigCalibration& result,
                           const std::map<std::string, camera::CameraSpec>& intrinsics,
                           double metres_per_unit, const std::string& unit_source,
                           spdlog::logger& log);

}  // namespace rigcal::cli
