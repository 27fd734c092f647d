// SPDX-License-Identifier: Apache-2.0
#pragma once
// ChArUco boards (OpenCV contrib aruco): a chessboard whose white squares hold ArUco markers, so
// that a view of part of the board still names every corner it shows. Views are found in the
// images of a source as the chessboard views are (target_views.h): the markers detected, the
// chessboard corners between them interpolated with sub-pixel refinement, each corner placed in
// the board frame (z = 0, the unit of square_size) by its id.

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern {

struct CharucoSpec {
  int squares_x = 5;         // squares along the board's x axis
  int squares_y = 7;         // squares along its y axis
  double square_size = 1.0;  // edge of one square: the unit of every position derived from it
  double marker_size = 0.7;  // edge of one marker, same unit, < square_size
  std::string dictionary = "DICT_4X4_50";  // OpenCV's predefined dictionary name
  int min_corners = 6;                     // fewer corners found: not a view
  // "<field>: <constraint>" for the first violated constraint (squares >= 2, 0 < marker_size <
  // square_size, a known dictionary with a marker for every white square, min_corners >= 4).
  Status Check() const;
};

// Parses "5x7" (squares along x and y) into squares_x, squares_y. Error text names the value.
Status ParseCharucoSquares(const std::string& text, CharucoSpec* spec);

// The ChArUco views of the images at `source` (a folder or folder/pattern), or of `images`
// when given (`source` then names them in messages). Errors as
// DetectChessboardViews': no images, unreadable, mixed resolutions, no board in any image.
Expected<CameraViews> DetectCharucoViews(const std::string& camera, const std::string& source,
                                         const CharucoSpec& board, const ImageStream& images = {});

// The board as an image to print (or to render test views from): `pixels_per_square` pixels per
// square, a white margin of one square. Error: an invalid spec.
Status DrawCharucoBoard(const CharucoSpec& board, int pixels_per_square, const std::string& path);

}  // namespace rigcal::pattern
