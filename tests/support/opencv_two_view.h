// SPDX-License-Identifier: Apache-2.0
#pragma once
// OpenCV's two-view relative pose as a peer of the VO in tests and evaluations: ORB features
// (cv::ORB, 1000 per image), brute-force Hamming matching with a cross check, the 5-point
// essential matrix in a RANSAC (cv::findEssentialMat, 1 px, 0.999) and cv::recoverPose.

#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::support {

// Pose of the camera of image `b` in the frame of the camera of image `a` (unit translation),
// for a pinhole camera without distortion with intrinsics K; nullopt when OpenCV finds none.
std::optional<Pose> OpenCvRelativePose(const cv::Mat& grey_a, const cv::Mat& grey_b,
                                       const cv::Matx33d& K);

// The same from KLT tracks instead of ORB matches: Shi-Tomasi corners of `frames.front()`
// tracked frame to frame (cv::calcOpticalFlowPyrLK, forward-backward checked) to
// `frames.back()`, then the 5-point RANSAC and cv::recoverPose.
std::optional<Pose> OpenCvKltRelativePose(const std::vector<cv::Mat>& frames, const cv::Matx33d& K);

}  // namespace rigcal::support
