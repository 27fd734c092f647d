// SPDX-License-Identifier: Apache-2.0
#pragma once
// Intrinsic calibration of one camera from its target views (thesis 3.4): pinhole with
// radial-tangential distortion through OpenCV calibrateCamera (k1, k2, p1, p2; k3 fixed at 0,
// as Kalibr's radtan), equidistant fisheye through cv::fisheye::calibrate (k1..k4), or the
// polynomial omnidirectional model (scaramuzza: OCamCalib's linear initialisation, then Ceres
// over centre, affine part, the degree-4 polynomial and the view poses; src/
// polynomial_calibration.h).
//
// Outlier views are rejected by their RMS reprojection error: after a first calibration, a view
// whose RMS exceeds max(median + 5 * 1.4826 * MAD, 2 * median) of the views' RMS (the threshold
// comes from the data) is dropped and the camera calibrated again from the others, until none
// is dropped (at most 3 rounds). When there are more views than `max_views`, that many are
// used, spread evenly over the sorted views (OpenCV's solvers are dense in the view poses);
// the statistics then cover every view, each with a PnP pose under the final intrinsics.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern {

struct IntrinsicsOptions {
  camera::CameraSpec::Model model =
      camera::CameraSpec::Model::kPinhole;  // pinhole, fisheye or scaramuzza
  int max_views = 80;                       // views given to the solver, >= 4
  int min_views = 4;                        // fewer usable views is an error, >= 3
  bool reject_outliers = true;
  // "<field>: <what>" for a bad option, else success.
  Status Check() const;
};

struct ViewStatistics {
  std::string file;
  int64_t t_ns = 0;
  int corners = 0;
  double rms_px = std::numeric_limits<double>::quiet_NaN();  // under the final intrinsics
  double max_px = std::numeric_limits<double>::quiet_NaN();
  bool used = false;      // in the final calibration
  bool rejected = false;  // dropped as an outlier
  Pose target_from_cam;   // PnP pose under the final intrinsics (q: target_from_cam, C: centre)
};

struct IntrinsicsResult {
  camera::CameraSpec spec;  // name, model, resolution, intrinsics, distortion
  double rms_px = 0.0;      // RMS reprojection error over the used views
  double rejection_threshold_px = std::numeric_limits<double>::quiet_NaN();
  int views_used = 0;
  int views_rejected = 0;
  std::vector<ViewStatistics> views;  // every view of the input, input order
  // Standard deviation of every camera parameter (Gauss-Newton over the parameters and the used
  // views' poses, scaled by the residuals' variance): names (fx, fy, cx, cy, then the
  // distortion coefficients) and values; both empty when unknown (the scaramuzza model, or
  // views that do not determine every parameter: parameter_std_error says why).
  std::vector<std::string> parameter_names;
  std::vector<double> parameter_std;
  std::string parameter_std_error;
};

// Calibrates the camera of `views`. Errors: too few views (fewer than options.min_views, or
// fewer left after rejection), OpenCV failing, or an estimate the camera model refuses
// (CameraSpec::Check's message).
Expected<IntrinsicsResult> CalibrateIntrinsics(const CameraViews& views,
                                               const IntrinsicsOptions& options);

// A text table: per view file, corners, RMS and max error [px], used / rejected; and the
// summary line with the intrinsics.
std::string FormatIntrinsics(const IntrinsicsResult& result, bool per_view);

}  // namespace rigcal::pattern
