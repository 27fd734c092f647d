// SPDX-License-Identifier: Apache-2.0
#pragma once
// Camera intrinsics from the files other tools write: a Kalibr camchain and a EuRoC / ASL
// sensor.yaml. Errors name the file, line and key.

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_spec.h"

namespace rigcal::io {

// The intrinsics of a Kalibr camchain file (cam0, cam1, ...: camera_model, intrinsics,
// distortion_model, distortion_coeffs, resolution, rostopic). Camera names are
// `rigcal_name` when present, else "cam0", "cam1", ...
Expected<std::vector<camera::CameraSpec>> ReadKalibrIntrinsics(const std::string& path);

// The intrinsics of a EuRoC / ASL camera `sensor.yaml` (mav0/camN/sensor.yaml): camera_model
// pinhole with distortion_model radial-tangential (as pinhole) or equidistant (as fisheye),
// intrinsics [fu, fv, cu, cv], distortion_coefficients, resolution [width, height]. `name` names
// the camera. Errors read "<path>:<line>: <key>: <what>".
Expected<camera::CameraSpec> ReadEurocSensorYaml(const std::string& path, const std::string& name);

}  // namespace rigcal::io
