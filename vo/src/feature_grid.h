// SPDX-License-Identifier: Apache-2.0
#pragma once
// Grid-bucketed feature detection: FAST corners, at most one per free grid cell (a cell is
// free when no tracked feature lies in it), strongest first, inside a validity mask (the
// lens's image area minus a border).

#include <opencv2/core.hpp>
#include <vector>

namespace rigcal::vo {

class FeatureGrid {
 public:
  // `mask`: CV_8UC1 of the image size, non-zero where features may be detected (may be empty:
  // everywhere but `border_px` from the image border).
  FeatureGrid(cv::Size image_size, int cell_px, int fast_threshold, int border_px, cv::Mat mask);

  // New corners for the free cells of the grid given the `existing` features, at most
  // `max_new`, strongest first. The FAST threshold is lowered (to 1/4 at least) when the image
  // has too little texture.
  std::vector<cv::Point2f> Detect(const cv::Mat& grey, const std::vector<cv::Point2f>& existing,
                                  int max_new) const;

  int CellOf(const cv::Point2f& p) const;
  int num_cells() const { return cols_ * rows_; }

 private:
  cv::Size size_;
  int cell_px_;
  int cols_;
  int rows_;
  int fast_threshold_;
  cv::Mat mask_;
};

}  // namespace rigcal::vo
