// SPDX-License-Identifier: Apache-2.0
#include "camchain_args.h"

#include "rigcal/io/result_camchain.h"

namespace rigcal::cli {

std::map<std::string, camera::CameraSpec> IntrinsicsOf(const io::RigConfig& config) {
  std::map<std::string, camera::CameraSpec> intrinsics;
  for (const io::CameraConfig& camera : config.cameras) {
    if (camera.spec) intrinsics[camera.name] = *camera.spec;
  }
  return intrinsics;
}

Status WriteResultCamchain(const std::string& path, const RigCalibration& result,
                           const std::map<std::string, camera::CameraSpec>& intrinsics,
                           double metres_per_unit, const std::string& unit_source,
                           spdlog::logger& log) {
  io::CamchainOptions options;
  options.intrinsics = intrinsics;
  options.metres_per_unit = metres_per_unit;
  options.unit_source = unit_source;
  auto written = io::WriteCamchain(path, result, options);
  if (!written) return Error{written.error()};
  log.info("wrote the camera chain {}{}", path,
           written->metric ? " (translations in metres, " + unit_source + ")" : "");
  if (!written->metric) {
    log.warn(
        "--camchain {}: translations in the master odometry's unit, not metres "
        "(rigcal_translation_unit); a metric master (`metric: true`), a target reference or "
        "--metric-* gives metres",
        path);
  }
  if (!written->no_intrinsics.empty()) {
    std::string names;
    for (const std::string& name : written->no_intrinsics) {
      names += (names.empty() ? "" : ", ") + name;
    }
    log.warn(
        "--camchain {}: no intrinsics for {} (give --config with the cameras' intrinsics): "
        "Kalibr cannot load those cameras",
        path, names);
  }
  return Status::Ok();
}

}  // namespace rigcal::cli
