// SPDX-License-Identifier: Apache-2.0
#include "support/opencv_two_view.h"

#include <Eigen/Core>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <vector>

namespace rigcal::support {

namespace {

// Relative pose from point correspondences (pixels) by the 5-point RANSAC and recoverPose.
std::optional<Pose> FivePoint(const std::vector<cv::Point2d>& pa,
                              const std::vector<cv::Point2d>& pb, const cv::Matx33d& K) {
  if (pa.size() < 8) return std::nullopt;
  cv::Mat inliers;
  const cv::Mat E = cv::findEssentialMat(pa, pb, cv::Mat(K), cv::RANSAC, 0.999, 1.0, inliers);
  if (E.rows != 3 || E.cols != 3) return std::nullopt;
  cv::Mat R, t;
  if (cv::recoverPose(E, pa, pb, cv::Mat(K), R, t, inliers) < 5) return std::nullopt;
  // OpenCV: x_b = R x_a + t. Camera b in a's frame: orientation R^T, centre -R^T t.
  Eigen::Matrix3d r_b_from_a;
  Eigen::Vector3d t_b;
  cv::cv2eigen(R, r_b_from_a);
  cv::cv2eigen(t, t_b);
  Pose b_in_a;
  b_in_a.q = Eigen::Quaterniond(r_b_from_a.transpose()).normalized();
  b_in_a.C = -(r_b_from_a.transpose() * t_b);
  return b_in_a;
}

}  // namespace

std::optional<Pose> OpenCvKltRelativePose(const std::vector<cv::Mat>& frames,
                                          const cv::Matx33d& K) {
  if (frames.size() < 2) return std::nullopt;
  std::vector<cv::Point2f> start;
  cv::goodFeaturesToTrack(frames.front(), start, 500, 0.01, 8);
  std::vector<cv::Point2f> current = start;
  std::vector<char> alive(start.size(), 1);
  for (size_t k = 1; k < frames.size(); ++k) {
    std::vector<cv::Point2f> next, back;
    std::vector<unsigned char> ok, ok_back;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(frames[k - 1], frames[k], current, next, ok, err);
    cv::calcOpticalFlowPyrLK(frames[k], frames[k - 1], next, back, ok_back, err);
    for (size_t i = 0; i < current.size(); ++i) {
      alive[i] = alive[i] && ok[i] && ok_back[i] && cv::norm(back[i] - current[i]) < 0.5;
    }
    current = next;
  }
  std::vector<cv::Point2d> pa, pb;
  for (size_t i = 0; i < start.size(); ++i) {
    if (!alive[i]) continue;
    pa.emplace_back(start[i]);
    pb.emplace_back(current[i]);
  }
  return FivePoint(pa, pb, K);
}

std::optional<Pose> OpenCvRelativePose(const cv::Mat& grey_a, const cv::Mat& grey_b,
                                       const cv::Matx33d& K) {
  const cv::Ptr<cv::ORB> orb = cv::ORB::create(1000);
  std::vector<cv::KeyPoint> key_a, key_b;
  cv::Mat desc_a, desc_b;
  orb->detectAndCompute(grey_a, cv::noArray(), key_a, desc_a);
  orb->detectAndCompute(grey_b, cv::noArray(), key_b, desc_b);
  if (desc_a.empty() || desc_b.empty()) return std::nullopt;
  cv::BFMatcher matcher(cv::NORM_HAMMING, /*crossCheck=*/true);
  std::vector<cv::DMatch> matches;
  matcher.match(desc_a, desc_b, matches);
  if (matches.size() < 8) return std::nullopt;
  std::vector<cv::Point2d> pa, pb;
  for (const cv::DMatch& m : matches) {
    pa.push_back(key_a[m.queryIdx].pt);
    pb.push_back(key_b[m.trainIdx].pt);
  }
  return FivePoint(pa, pb, K);
}

}  // namespace rigcal::support
