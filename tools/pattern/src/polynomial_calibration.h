// SPDX-License-Identifier: Apache-2.0
#pragma once
// Intrinsic calibration of the polynomial omnidirectional model (thesis 3.2.2, Scaramuzza's
// OCamCalib [SMS06]; rigcal's `scaramuzza` camera, camera_spec.h) from views of a planar target.
//
// 1. Linear initialisation (Scaramuzza et al. 2006), centre at the image centre, no affine
//    distortion: per view, the corners' pixels m and target points (X, Y) give the first two
//    rows of [r1 r2 t] up to scale from m_x P_y - m_y P_x = 0, their sign chosen so that the
//    view alone gives F(0) < 0; orthonormality gives r31, r32 (two signs, the one that fits the
//    view better is kept); then one linear least-squares system over all views for the
//    polynomial F(rho) = a0 + a2 rho^2 + ... + aN rho^N (a1 = 0, as OCamCalib) and every view's
//    t3, each view then turned to face the camera.
// 2. Ceres (Levenberg-Marquardt) on the reprojection error over the centre, the affine part
//    [c, d] (e = 0: a rotation about the optical axis is the views' gauge), the polynomial and
//    every view's pose. Projection solves rho z + F(rho) sqrt(x^2 + y^2) = 0 for the smallest
//    positive rho in doubles, then takes one Newton step in Ceres' Jets, whose derivative part
//    is then the implicit-function derivative of the root.
// 3. The degree N (3 to 7) is chosen by the data: each degree from its own linear start, the
//    smallest BIC (2 n ln(RSS / 2n) + N ln(2n) over n corners) among the valid cameras.
// The polynomial is estimated in rho / s (s = half the larger image side) so that its
// coefficients are of one magnitude, and written back in pixels.

#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern::internal {

// Calibrates from the views at `indices` (>= 3 with >= 6 corners each) and fills spec's
// poly, center and affine (inverse_poly empty: fitted when the model is built); *rms_px is the
// RMS reprojection error over the corners. Errors name the camera: a target off its z = 0
// plane, a linear initialisation that finds no camera in front of the target, Ceres failing.
Status CalibratePolynomial(const CameraViews& views, const std::vector<size_t>& indices,
                           camera::CameraSpec* spec, double* rms_px);

}  // namespace rigcal::pattern::internal
