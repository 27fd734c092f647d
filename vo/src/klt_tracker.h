// SPDX-License-Identifier: Apache-2.0
#pragma once
// Pyramidal KLT tracking between consecutive images (OpenCV calcOpticalFlowPyrLK on pyramids
// and image derivatives built once per image) with a forward-backward consistency check.

#include <opencv2/core.hpp>
#include <vector>

namespace rigcal::vo {

struct KltOptions {
  int window_px = 21;
  int pyramid_levels = 3;
  double max_fb_error_px = 0.5;
  int max_iterations = 10;
  double epsilon = 0.03;
};

class KltTracker {
 public:
  explicit KltTracker(KltOptions options = {}) : options_(options) {}

  // Builds the pyramid of the next image (CV_8UC1); the current one becomes the previous.
  void AddImage(const cv::Mat& grey);
  // Forgets the images.
  void Reset();
  bool has_previous() const { return has_previous_; }

  // Tracks `previous` points of the previous image into the current one. `guesses` (empty or
  // one per point) are predicted positions. Sets (*tracked)[i] and (*ok)[i] = 1 for points
  // that were tracked, lie inside the image and pass the forward-backward check. `fb_px` (may
  // be null) receives the forward-backward distances of the points tracked both ways, pixels.
  void Track(const std::vector<cv::Point2f>& previous, const std::vector<cv::Point2f>& guesses,
             std::vector<cv::Point2f>* tracked, std::vector<unsigned char>* ok,
             std::vector<double>* fb_px = nullptr) const;

 private:
  KltOptions options_;
  std::vector<cv::Mat> previous_pyramid_;
  std::vector<cv::Mat> current_pyramid_;
  cv::Size size_;
  bool has_current_ = false;
  bool has_previous_ = false;
};

}  // namespace rigcal::vo
