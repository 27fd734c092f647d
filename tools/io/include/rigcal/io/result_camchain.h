// SPDX-License-Identifier: Apache-2.0
#pragma once
// A Kalibr camchain of a calibration result (`--camchain` of solve, calib, replay, run): cam0 is
// the master, cam1..camN the slaves; every camera with intrinsics in the rig config gets the
// complete Kalibr entry (camera_model, intrinsics, distortion_model, distortion_coeffs,
// resolution, rostopic; kalibr_camchain.h), and T_cn_cnm1 (points from camera n-1 to camera n,
// 4x4 row-major) is in metres when the scale of the result is known. Otherwise the translations
// are in the master odometry's unit, and every camera says so in `rigcal_translation_unit`
// (Kalibr ignores keys it does not know; its own camchains are in metres).

#include <limits>
#include <map>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/camera/camera_spec.h"

namespace rigcal::io {

struct CamchainOptions {
  // Every camera to write, master first; empty = the master and then every usable slave.
  std::vector<std::string> camera_order;
  // Intrinsics by camera name (the rig config's cameras); a camera without any is written with
  // its extrinsics only.
  std::map<std::string, camera::CameraSpec> intrinsics;
  // Metres per master unit of the result's C: 1 when C is already in metres (a metric master,
  // a target reference, `--metric-*`); NaN when unknown.
  double metres_per_unit = std::numeric_limits<double>::quiet_NaN();
  std::string unit_source;  // how the unit is known ("metric master", ...), for the comment
};

// What was written, for the command's warnings.
struct CamchainWritten {
  bool metric = false;                     // T_cn_cnm1 in metres
  std::vector<std::string> no_intrinsics;  // cameras written without intrinsics
};

// Writes the camchain atomically. Errors name the path and an unknown camera, a master not
// listed first, a slave without a usable estimate, or a camera model Kalibr cannot hold.
Expected<CamchainWritten> WriteCamchain(const std::string& path, const RigCalibration& result,
                                        const CamchainOptions& options = {});

}  // namespace rigcal::io
