// SPDX-License-Identifier: Apache-2.0
#include "klt_tracker.h"

#include <cmath>
#include <opencv2/video/tracking.hpp>

namespace rigcal::vo {

void KltTracker::AddImage(const cv::Mat& grey) {
  std::swap(previous_pyramid_, current_pyramid_);
  has_previous_ = has_current_ && grey.size() == size_;
  const cv::Size window(options_.window_px, options_.window_px);
  // With the Scharr derivatives of every level: calcOpticalFlowPyrLK would otherwise compute
  // them for the whole image at each call, and each image is the source of two calls (backward
  // in its own frame, forward in the next).
  cv::buildOpticalFlowPyramid(grey, current_pyramid_, window, options_.pyramid_levels, true);
  size_ = grey.size();
  has_current_ = true;
}

void KltTracker::Reset() {
  has_current_ = false;
  has_previous_ = false;
}

void KltTracker::Track(const std::vector<cv::Point2f>& previous,
                       const std::vector<cv::Point2f>& guesses, std::vector<cv::Point2f>* tracked,
                       std::vector<unsigned char>* ok, std::vector<double>* fb_px) const {
  const size_t n = previous.size();
  ok->assign(n, 0);
  *tracked = guesses.size() == n ? guesses : previous;
  if (!has_previous_ || n == 0) return;
  const cv::Size window(options_.window_px, options_.window_px);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS,
                                  options_.max_iterations, options_.epsilon);
  // No error output: OpenCV would measure every point's window residual once more for it.
  std::vector<unsigned char> forward_ok, backward_ok;
  cv::calcOpticalFlowPyrLK(previous_pyramid_, current_pyramid_, previous, *tracked, forward_ok,
                           cv::noArray(), window, options_.pyramid_levels, criteria,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  // Back from the tracked points, started where they came from: a consistent track returns to
  // its start at the base level alone (a third of a pyramidal pass); a slipped one does not.
  std::vector<cv::Point2f> back = previous;
  cv::calcOpticalFlowPyrLK(current_pyramid_, previous_pyramid_, *tracked, back, backward_ok,
                           cv::noArray(), window, 0, criteria, cv::OPTFLOW_USE_INITIAL_FLOW);
  const double max_fb2 = options_.max_fb_error_px * options_.max_fb_error_px;
  const float w = static_cast<float>(size_.width - 1);
  const float h = static_cast<float>(size_.height - 1);
  if (fb_px != nullptr) fb_px->clear();
  for (size_t i = 0; i < n; ++i) {
    if (!forward_ok[i] || !backward_ok[i]) continue;
    const cv::Point2f& p = (*tracked)[i];
    if (!(p.x >= 0.f && p.y >= 0.f && p.x <= w && p.y <= h)) continue;
    const cv::Point2f d = back[i] - previous[i];
    const double fb2 = d.x * d.x + d.y * d.y;
    if (fb_px != nullptr) fb_px->push_back(std::sqrt(fb2));
    if (fb2 > max_fb2) continue;
    (*ok)[i] = 1;
  }
}

}  // namespace rigcal::vo
