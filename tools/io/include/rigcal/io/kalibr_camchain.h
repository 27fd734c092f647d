// SPDX-License-Identifier: Apache-2.0
#pragma once
// A complete Kalibr camchain YAML (kalibr_calibrate_cameras' camchain.yaml, read by Kalibr's
// own config reader): per camera camN camera_model (pinhole), intrinsics [fu, fv, pu, pv],
// distortion_model (radtan for rigcal's pinhole, equidistant for its fisheye),
// distortion_coeffs (4), resolution [width, height], rostopic, and for N >= 1 T_cn_cnm1 (4x4,
// row-major, takes points from camera N-1 to camera N). rigcal_name (a rigcal extension, also
// read back by rigcal) names the camera.

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_spec.h"

namespace rigcal::io {

struct CamchainEntry {
  camera::CameraSpec spec;
  // The camera's pose in the first camera's frame (q, C; scale ignored). Needed for every
  // camera but the first; T_cn_cnm1 is computed from consecutive entries.
  std::optional<Similarity> cam0_from_cam;
  // Kalibr's omni model (Mei's unified model, cv::omnidir): camera_model omni, intrinsics
  // [xi, fu, fv, pu, pv] with fu..pv from spec.intrinsics, distortion radtan from
  // spec.distortion (k1, k2, p1, p2). Unset: the model of spec.
  std::optional<double> omni_xi;
  // False: spec holds only the name; camera_model, intrinsics, distortion, resolution and
  // rostopic are left out (not a complete Kalibr camera).
  bool intrinsics_known = true;
  // Unless empty, written as `rigcal_translation_unit` (a rigcal extension): "m", or
  // "master_odometry_unit" when T_cn_cnm1's translation is not metric.
  std::string translation_unit;
};

// Writes `cameras` atomically to `path`, `comment` first as "# " lines. Errors: no camera, a
// scaramuzza camera (no Kalibr equivalent here), a pinhole with 5 coefficients (Kalibr's radtan
// has 4), a camera after the first without cam0_from_cam, or the write failing (naming path).
[[nodiscard]] Status WriteKalibrCamchain(const std::string& path,
                                         const std::vector<CamchainEntry>& cameras,
                                         const std::string& comment);

}  // namespace rigcal::io
