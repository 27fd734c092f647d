// SPDX-License-Identifier: Apache-2.0
#pragma once
// Camera models: projection of points in the camera frame to pixels and back to unit bearing
// vectors, with Jacobians. VO works on bearing vectors only, so the same pipeline runs on
// pinhole, fisheye (Kannala–Brandt) and omnidirectional (Scaramuzza, thesis 3.2.2) lenses.
//
// Camera frame: x right, y down, z forward (optical axis), as OpenCV and Kalibr.
// Pixels: (u, v) = (column, row); (0, 0) is the centre of the top-left pixel, so the image
// covers [-0.5, width - 0.5] x [-0.5, height - 0.5].
// Models are built from a CameraSpec by MakeCameraModel (camera_spec.h, which documents the
// three models' equations). A model is immutable once shared: every const method may be
// called concurrently from any thread; Project and Unproject do not allocate.

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <string>

namespace rigcal::camera {

class CameraModel {
 public:
  virtual ~CameraModel() = default;

  // Model name as written in the config: "pinhole", "fisheye" or "scaramuzza".
  virtual std::string type() const = 0;
  int width() const { return width_; }
  int height() const { return height_; }

  // Pixel of a point in the camera frame (any distance), or nullopt when the point is outside
  // the model's field of view (e.g. behind a pinhole camera). `jacobian` (optional): d pixel /
  // d point, 2x3.
  virtual std::optional<Eigen::Vector2d> Project(
      const Eigen::Vector3d& point, Eigen::Matrix<double, 2, 3>* jacobian = nullptr) const = 0;

  // Unit bearing vector of a pixel, or nullopt outside the model's valid domain (beyond the
  // max field angle). Pixels outside the image but inside the domain are unprojected too.
  // `jacobian` (optional): d bearing / d pixel, 3x2.
  virtual std::optional<Eigen::Vector3d> Unproject(
      const Eigen::Vector2d& pixel, Eigen::Matrix<double, 3, 2>* jacobian = nullptr) const = 0;

  // Half of the widest angle between the optical axis and a valid bearing, degrees.
  virtual double MaxFieldAngleDeg() const = 0;

  // Angular size of one pixel near the image centre, radians (for thresholds in bearing space).
  virtual double PixelAngle() const = 0;

  virtual std::unique_ptr<CameraModel> Clone() const = 0;

  // Rolling shutter: time from the exposure of the top row to the bottom row's, seconds (0 =
  // global shutter). Row v is exposed v / (height - 1) of it after the frame's stamp, which is
  // the top row's exposure time. Not part of the projection: the VO, which knows the camera's
  // motion, moves the observations of later rows to the stamp (vo/src/rolling_shutter.h). Set
  // once by MakeCameraModel (or whoever builds the model) before the model is shared; Clone
  // keeps it.
  double rolling_shutter_s() const { return rolling_shutter_s_; }
  void set_rolling_shutter_s(double readout_s) { rolling_shutter_s_ = readout_s; }

  // True when `pixel` lies inside the image shrunk by `border` pixels on every side.
  bool InImage(const Eigen::Vector2d& pixel, double border = 0.0) const {
    return pixel.x() >= border - 0.5 && pixel.x() <= width_ - 0.5 - border &&
           pixel.y() >= border - 0.5 && pixel.y() <= height_ - 0.5 - border;
  }

 protected:
  CameraModel(int width, int height) : width_(width), height_(height) {}
  CameraModel(const CameraModel&) = default;
  CameraModel& operator=(const CameraModel&) = default;

 private:
  int width_ = 0;
  int height_ = 0;
  double rolling_shutter_s_ = 0.0;
};

}  // namespace rigcal::camera
