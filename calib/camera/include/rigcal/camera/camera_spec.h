// SPDX-License-Identifier: Apache-2.0
#pragma once
// CameraSpec: a plain description of one camera as written in the rig config (docs/config.md,
// `cameras:`), and the factory that turns it into a CameraModel. yaml-cpp never gets here: the
// config loader of tools/ fills this struct (tools/include/rigcal/io/config_sections.h).
//
// Conventions shared by every model (see camera_model.h):
//   camera frame  x right, y down, z forward (optical axis), as OpenCV and Kalibr;
//   pixels        (u, v) = (column, row); (0, 0) is the centre of the top-left pixel, so the
//                 image covers [-0.5, width - 0.5] x [-0.5, height - 0.5] (OpenCV, Kalibr);
//   field angle   the angle between a bearing and the optical axis +z, in [0, 180) degrees.
//
// The three models:
//
// pinhole (radial-tangential, OpenCV / Kalibr "radtan"):
//   (x', y') = (x / z, y / z), r^2 = x'^2 + y'^2, R = 1 + k1 r^2 + k2 r^4 + k3 r^6
//   x'' = x' R + 2 p1 x' y' + p2 (r^2 + 2 x'^2)
//   y'' = y' R + p1 (r^2 + 2 y'^2) + 2 p2 x' y'
//   u = fx x'' + cx,  v = fy y'' + cy.            Points with z <= 0 are rejected.
//
// fisheye (Kannala-Brandt equidistant, OpenCV fisheye / Kalibr "equidistant"):
//   theta = atan2(sqrt(x^2 + y^2), z) (works beyond 90 degrees, i.e. for z < 0),
//   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
//   u = fx theta_d x / sqrt(x^2 + y^2) + cx,  v = fy theta_d y / sqrt(x^2 + y^2) + cy.
//
// scaramuzza (polynomial omnidirectional model of thesis 3.2.2 / OCamCalib, [SMS06]):
//   F(rho) = a0 + a1 rho + a2 rho^2 + ... + aN rho^N          (`poly`, a0 < 0)
//   A pixel maps to the sensor-plane point m = (mx, my) by undoing the affine part
//       u = cx + mx + e my,   v = cy + d mx + c my              (`center`, `affine` [c, d, e])
//   and its bearing is the normalisation of (mx, my, -F(|m|)).   (Unprojection, exact.)
//   Projection solves rho z + F(rho) sqrt(x^2 + y^2) = 0 for rho (the inverse of the above)
//   and sets m = rho (x, y) / sqrt(x^2 + y^2). `inverse_poly` is the OCamCalib approximation
//       rho ~ b0 + b1 phi + b2 phi^2 + ...,   phi = theta - 90 deg (radians),
//   used as the starting point of a Newton refinement, so Project is the exact inverse of
//   Unproject to ~1e-12 px whatever the accuracy of `inverse_poly`.
//   Relation to OCamCalib (ocam_functions.c cam2world / world2cam): OCamCalib's camera frame
//   is (x_o, y_o, z_o) = (y, x, -z) (x_o along image rows, z_o backwards, hence a0 < 0 and
//   "z = -F(rho)"), its pixel is (row, column), and its affine part is
//       row = c x_o' + d y_o' + xc,   column = e x_o' + y_o' + yc.
//   So `poly`, `inverse_poly` and `affine` are copied unchanged from calib_results.txt, while
//   `center` is [column, row] = [yc, xc] (OCamCalib lists "xc yc" as row, column; subtract 1
//   when the values come from the MATLAB toolbox's 1-based pixel coordinates).

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::camera {

struct CameraSpec {
  enum class Model { kPinhole, kFisheye, kScaramuzza };

  std::string name;  // camera name, for messages only (may be empty)
  Model model = Model::kPinhole;
  int width = 0;   // image size in pixels, > 0 (config `resolution: [width, height]`)
  int height = 0;  //

  // pinhole, fisheye: [fx, fy, cx, cy] in pixels; fx, fy > 0; principal point inside the
  // image. Unused (all zero) for scaramuzza.
  std::array<double, 4> intrinsics = {0.0, 0.0, 0.0, 0.0};
  // pinhole: [k1, k2, p1, p2] or [k1, k2, p1, p2, k3]; fisheye: [k1, k2, k3, k4];
  // empty = no distortion. Must be empty for scaramuzza.
  std::vector<double> distortion;

  // scaramuzza only (empty / defaults for the other models).
  std::vector<double> poly;                        // a0..aN (N <= 20), a0 < 0; see above
  std::vector<double> inverse_poly;                // b0..bM; empty: fitted when the model is built
  std::array<double, 2> center = {0.0, 0.0};       // [cx, cy] pixels, inside the image
  std::array<double, 3> affine = {1.0, 0.0, 0.0};  // [c, d, e], c - d e > 0

  // Half field of view in degrees: the largest field angle the model accepts. Project rejects
  // points beyond it, Unproject pixels beyond its image. 0 = automatic: the field angle of
  // the farthest image corner, limited to where the lens model stops being one-to-one
  // (distortion folding back) and to 89 degrees (pinhole) / 179 degrees (fisheye,
  // scaramuzza). Otherwise in (0, 90) for pinhole, (0, 180) for the others, and the model
  // must be one-to-one up to it (else an error). Give it for circular fisheye images whose
  // corners see nothing (a 186-degree lens: 93).
  double max_field_angle_deg = 0.0;

  // Rolling shutter (config `rolling_shutter_ms`): the time from the exposure of the top image
  // row to the bottom row's, seconds; row v is exposed v / (height - 1) of it after the frame's
  // stamp (the stamp is the top row's). 0 = global shutter. In [0, 1 s). The VO moves each
  // observation to the stamp's time with its own motion estimate (camera_model.h).
  double rolling_shutter_s = 0.0;

  // Success when MakeCameraModel will succeed, else the first problem of the spec as
  // "<field>: <what>", <field> being the config key at fault (`resolution`, `intrinsics`,
  // `distortion`, `poly`, ...). Besides the ranges above this checks the lens model itself:
  // monotonic distortion up to max_field_angle_deg, a scaramuzza `poly` whose field angle
  // increases with the radius, an `inverse_poly` that inverts `poly` to within 1 px.
  Status Check() const;
};

// "pinhole", "fisheye", "scaramuzza".
std::string_view ModelName(CameraSpec::Model model);
// Inverse of ModelName; nullopt for anything else.
std::optional<CameraSpec::Model> ModelFromName(std::string_view name);

// The camera model of a spec. The error is Check()'s message "<field>: <what>".
// The model is immutable: its const methods may be called from any thread concurrently.
Expected<std::unique_ptr<CameraModel>> MakeCameraModel(const CameraSpec& spec);

// A scaramuzza spec approximating an ideal equidistant ("f-theta") fisheye whose pixel radius
// is focal_px * theta (theta = field angle, radians), centred at (cx, cy), with
// max_field_angle_deg as given (e.g. 93 for the 186-degree lenses of thesis 5.7), no affine
// distortion. `poly` holds even powers only (a0 = -focal_px, a1 = 0 as OCamCalib) fitted so that
// the pixel radius of every field angle up to max_field_angle_deg is within 1e-3 px of
// focal_px * theta; `inverse_poly` is left empty (fitted by MakeCameraModel). Used for simulated
// omnidirectional cameras: write the returned poly into a config file with 17 significant
// digits. Errors: focal_px <= 0, image size <= 0, centre outside the image,
// max_field_angle_deg outside (0, 140], or a fit that misses the tolerance.
Expected<CameraSpec> ScaramuzzaSpecForEquidistant(const std::string& name, int width, int height,
                                                  double focal_px, double cx, double cy,
                                                  double max_field_angle_deg);

}  // namespace rigcal::camera
