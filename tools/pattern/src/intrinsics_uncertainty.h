// SPDX-License-Identifier: Apache-2.0
#pragma once
// The standard deviations of a calibrated camera's parameters: the Gauss-Newton covariance of
// the reprojection least squares over the parameters and every used view's target pose, the
// poses eliminated (Schur complement), scaled by the residuals' variance per axis
// (sum of squares / (2 corners - parameters - 6 views)). Derivatives: central differences for
// the camera parameters, the model's own Jacobian for the poses.

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/pattern/intrinsics.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern::internal {

// Names of the parameters ParameterStdDev reports, in its order: fx, fy, cx, cy and the
// distortion coefficients (k1, k2, p1, p2 for pinhole radtan; k1..k4 for the equidistant
// fisheye). Empty for the scaramuzza model (not computed: its projection goes through the
// fitted inverse polynomial).
std::vector<std::string> ParameterNames(const camera::CameraSpec& spec);

// sigma of every parameter of `spec` given the views `used` (indices into views.views) with
// their poses under `spec` (stats[i].target_from_cam). Errors: a model without a parameter list
// (scaramuzza), too few residuals for the unknowns, a corner that does not project, or
// parameters the views do not determine (a singular normal matrix).
Expected<std::vector<double>> ParameterStdDev(const camera::CameraSpec& spec,
                                              const CameraViews& views,
                                              const std::vector<ViewStatistics>& stats,
                                              const std::vector<size_t>& used);

}  // namespace rigcal::pattern::internal
