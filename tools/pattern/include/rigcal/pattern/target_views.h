// SPDX-License-Identifier: Apache-2.0
#pragma once
// Views of a calibration target by one camera: for every image (or detection file) the pixel
// coordinates of the target's corners and the same corners in the target frame (metres, or the
// unit of the given square size), z = 0 for the planar targets read here.
//
// Two sources:
//   images      a folder of images (png, jpg, jpeg, bmp, pgm, ppm, tif, tiff), optionally a
//               file name pattern with '*' and '?' ("data/left*.jpg"), searched for a
//               chessboard of cols x rows inner corners (OpenCV findChessboardCorners, then
//               cornerSubPix on an 11x11 window);
//   detections  a folder of AprilGrid corner CSVs, one per frame, named <t_ns>.csv, columns
//                 #ts,tag_rows,tag_cols,tag_size,tag_spacing,kp_x,kp_y,p_x,p_y,p_z,tag_id,corner_idx
//               (the EuRoC / yac format: kp = distorted pixel, p = corner in the target frame).
//               The resolution is not in the files: give it.
//
// Every view has a key that pairs the views of several cameras taken at the same instant:
// the digits of its file stem as a number, taken as nanoseconds when >= 1e12 (a time stamp, as
// EuRoC's "1404733405732800000.csv"), else as a frame number whose t_ns is that number of
// seconds ("left07.jpg" -> 7 s), so that trajectories written from the views are ordinary pose
// files.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::pattern {

struct TargetView {
  std::string file;                            // the image or CSV it came from
  int64_t t_ns = 0;                            // pairing key, see above
  std::vector<Eigen::Vector2d> pixels;         // distorted pixel coordinates (u, v)
  std::vector<Eigen::Vector3d> target_points;  // the same corners in the target frame
};

struct CameraViews {
  std::string camera;  // camera name
  int width = 0;       // image size in pixels
  int height = 0;
  int files = 0;                  // images / CSV files read
  std::vector<std::string> none;  // files without a (complete) target, by name
  std::vector<TargetView> views;  // views with a target, sorted by t_ns
};

struct ChessboardSpec {
  int cols = 9;              // inner corners per row
  int rows = 6;              // inner corners per column
  double square_size = 1.0;  // edge of one square, the unit of every position derived from it
  // "cols x rows: <what>" when not cols, rows >= 2 and square_size > 0, else success.
  Status Check() const;
};

// One 8-bit grey image of a stream of images (an LCM image log, ...): width x height bytes,
// row-major without padding; `name` labels it in messages and per-view statistics, `t_ns` is
// its pairing key (see above).
struct GreyImage {
  std::string name;
  int64_t t_ns = 0;
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;
};

// Fills *image and returns true, returns false at the end of the stream, or an error (which
// stops the detection and is passed on).
using ImageStream = std::function<Expected<bool>(GreyImage* image)>;

// Parses "9x6" into cols = 9, rows = 6 (keeps square_size). Error text names the value.
Status ParseChessboardSize(const std::string& text, ChessboardSpec* spec);

// The chessboard views of the images at `source` (a folder or a folder/pattern, see above), or
// of `images` when given (then `source` only names them in messages, e.g. the log file).
// Errors name the path: no images, an unreadable image, images of different sizes ("mixed
// resolutions: a.png is 640x480, b.png is 752x480"), or no chessboard found in any image.
// A view with fewer corners than the board has is not a view (listed in `none`).
Expected<CameraViews> DetectChessboardViews(const std::string& camera, const std::string& source,
                                            const ChessboardSpec& board,
                                            const ImageStream& images = {});

// The AprilGrid views of the <t_ns>.csv files in `folder`, for an image of width x height.
// Errors name the file and line (a malformed row, a corner outside the image) or say that no
// file holds a detection. Frames with fewer than `min_corners` corners are listed in `none`.
Expected<CameraViews> ReadAprilGridViews(const std::string& camera, const std::string& folder,
                                         int width, int height, int min_corners = 12);

// The views of `source`: AprilGrid CSVs when it is a folder holding *.csv files (then width and
// height must be given), else chessboard images (width, height: 0 or the images' size, else an
// error). Errors as the two readers'.
Expected<CameraViews> LoadCameraViews(const std::string& camera, const std::string& source,
                                      const ChessboardSpec& board, int width, int height);

// True when `source` names AprilGrid CSVs (a folder holding *.csv files) rather than images.
bool IsDetectionFolder(const std::string& source);

}  // namespace rigcal::pattern
