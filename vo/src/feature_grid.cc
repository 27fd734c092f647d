// SPDX-License-Identifier: Apache-2.0
#include "feature_grid.h"

#include <algorithm>
#include <opencv2/features2d.hpp>

namespace rigcal::vo {

FeatureGrid::FeatureGrid(cv::Size image_size, int cell_px, int fast_threshold, int border_px,
                         cv::Mat mask)
    : size_(image_size),
      cell_px_(std::max(4, cell_px)),
      cols_((image_size.width + cell_px_ - 1) / cell_px_),
      rows_((image_size.height + cell_px_ - 1) / cell_px_),
      fast_threshold_(std::max(1, fast_threshold)) {
  mask_ = cv::Mat::zeros(image_size, CV_8UC1);
  const cv::Rect inner(border_px, border_px, image_size.width - 2 * border_px,
                       image_size.height - 2 * border_px);
  if (inner.width > 0 && inner.height > 0) mask_(inner).setTo(255);
  if (!mask.empty() && mask.size() == image_size && mask.type() == CV_8UC1) {
    cv::bitwise_and(mask_, mask, mask_);
  }
}

int FeatureGrid::CellOf(const cv::Point2f& p) const {
  const int cx = std::clamp(static_cast<int>(p.x) / cell_px_, 0, cols_ - 1);
  const int cy = std::clamp(static_cast<int>(p.y) / cell_px_, 0, rows_ - 1);
  return cy * cols_ + cx;
}

std::vector<cv::Point2f> FeatureGrid::Detect(const cv::Mat& grey,
                                             const std::vector<cv::Point2f>& existing,
                                             int max_new) const {
  std::vector<cv::Point2f> out;
  if (max_new <= 0 || grey.empty() || grey.size() != size_) return out;
  std::vector<char> occupied(num_cells(), 0);
  for (const cv::Point2f& p : existing) occupied[CellOf(p)] = 1;
  const int free_cells = static_cast<int>(std::count(occupied.begin(), occupied.end(), 0));
  if (free_cells == 0) return out;

  std::vector<int> best(num_cells(), -1);
  std::vector<cv::KeyPoint> corners;
  for (int threshold = fast_threshold_; threshold >= std::max(1, fast_threshold_ / 4);
       threshold /= 2) {
    corners.clear();
    cv::FAST(grey, corners, threshold, true);
    std::fill(best.begin(), best.end(), -1);
    int filled = 0;
    for (int i = 0; i < static_cast<int>(corners.size()); ++i) {
      const cv::Point2f& p = corners[i].pt;
      const int x = static_cast<int>(p.x);
      const int y = static_cast<int>(p.y);
      if (x < 0 || y < 0 || x >= size_.width || y >= size_.height) continue;
      if (!mask_.at<unsigned char>(y, x)) continue;
      const int cell = CellOf(p);
      if (occupied[cell]) continue;
      if (best[cell] < 0) {
        ++filled;
        best[cell] = i;
      } else if (corners[i].response > corners[best[cell]].response) {
        best[cell] = i;
      }
    }
    if (filled * 2 >= free_cells || filled >= max_new || threshold / 2 < fast_threshold_ / 4) break;
  }
  std::vector<int> picked;
  for (int cell = 0; cell < num_cells(); ++cell) {
    if (best[cell] >= 0) picked.push_back(best[cell]);
  }
  std::sort(picked.begin(), picked.end(),
            [&](int a, int b) { return corners[a].response > corners[b].response; });
  for (int i = 0; i < static_cast<int>(picked.size()) && i < max_new; ++i) {
    out.push_back(corners[picked[i]].pt);
  }
  return out;
}

}  // namespace rigcal::vo
