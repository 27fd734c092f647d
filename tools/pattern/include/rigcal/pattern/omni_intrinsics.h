// SPDX-License-Identifier: Apache-2.0
#pragma once
// Omnidirectional intrinsics: Mei's unified model through OpenCV contrib's cv::omnidir (ccalib,
// Debian's libopencv-contrib-dev), Kalibr's "omni" camera model with radtan distortion. A point
// X of the camera frame goes to the unit sphere, is projected from the point (0, 0, -xi),
//     (x, y) = (X / (Z + xi |X|), Y / (Z + xi |X|)),
// then distorted (k1, k2, p1, p2, as pinhole radtan) and mapped by fu, fv, pu, pv (no skew).
// Kalibr's camchain writes it as camera_model omni, intrinsics [xi, fu, fv, pu, pv]
// (io/kalibr_camchain.h, CamchainEntry::omni_xi). rigcal's own camera models (camera_spec.h) have
// no unified model: the result is the camchain entry and the statistics below. `rigcal
// intrinsics --model scaramuzza` puts rigcal's polynomial model into the rig config and this one
// into the camchain (Kalibr has no polynomial model).

#include <array>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/io/kalibr_camchain.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern {

struct OmniIntrinsics {
  std::string camera;
  int width = 0;
  int height = 0;
  double xi = 0.0;
  std::array<double, 4> intrinsics = {0, 0, 0, 0};  // fu, fv, pu, pv
  std::array<double, 4> distortion = {0, 0, 0, 0};  // k1, k2, p1, p2
  double rms_px = 0.0;                              // over the views used
  int views_used = 0;   // views cv::omnidir kept (it drops views it cannot initialise)
  int views_given = 0;  // views given to it (at most max_views, spread over the input)

  // The camchain entry of this camera (spec: pinhole-shaped intrinsics and radtan
  // distortion, omni_xi set).
  io::CamchainEntry ToCamchainEntry() const;
};

// cv::omnidir::calibrate on at most `max_views` views spread over `views` (>= 4). Errors: fewer
// than 4 views, OpenCV failing (its message), fewer than 4 views kept.
Expected<OmniIntrinsics> CalibrateOmni(const CameraViews& views, int max_views);

// One line: xi, fu, fv, pu, pv, distortion, RMS, views.
std::string FormatOmni(const OmniIntrinsics& omni);

}  // namespace rigcal::pattern
