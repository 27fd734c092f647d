// SPDX-License-Identifier: Apache-2.0
#include "support/opencv_handeye.h"

#include <cmath>

// OpenCV 4.6 headers do enum arithmetic that C++20 deprecates; keep the build log clean.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#pragma GCC diagnostic pop

namespace rigcal::support {
namespace {

cv::Mat ToCvRotation(const Eigen::Matrix3d& R) {
  cv::Mat m(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) m.at<double>(r, c) = R(r, c);
  }
  return m;
}

cv::Mat ToCvVector(const Eigen::Vector3d& v) {
  return (cv::Mat_<double>(3, 1) << v.x(), v.y(), v.z());
}

cv::HandEyeCalibrationMethod ToCv(HandEyeMethod method) {
  switch (method) {
    case HandEyeMethod::kTsai:
      return cv::CALIB_HAND_EYE_TSAI;
    case HandEyeMethod::kPark:
      return cv::CALIB_HAND_EYE_PARK;
    case HandEyeMethod::kHoraud:
      return cv::CALIB_HAND_EYE_HORAUD;
    case HandEyeMethod::kAndreff:
      return cv::CALIB_HAND_EYE_ANDREFF;
    case HandEyeMethod::kDaniilidis:
      return cv::CALIB_HAND_EYE_DANIILIDIS;
  }
  return cv::CALIB_HAND_EYE_TSAI;
}

}  // namespace

std::string ToString(HandEyeMethod method) {
  switch (method) {
    case HandEyeMethod::kTsai:
      return "TSAI";
    case HandEyeMethod::kPark:
      return "PARK";
    case HandEyeMethod::kHoraud:
      return "HORAUD";
    case HandEyeMethod::kAndreff:
      return "ANDREFF";
    case HandEyeMethod::kDaniilidis:
      return "DANIILIDIS";
  }
  return "?";
}

HandEyeResult OpenCvHandEye(const std::vector<Pose>& master_poses,
                            const std::vector<Pose>& slave_poses, HandEyeMethod method) {
  HandEyeResult result;
  result.method = method;
  if (master_poses.size() != slave_poses.size() || master_poses.size() < 3) {
    result.error = "need at least 3 time-corresponding poses of both cameras";
    return result;
  }
  std::vector<cv::Mat> R_gripper2base, t_gripper2base, R_target2cam, t_target2cam;
  const size_t n = master_poses.size();
  R_gripper2base.reserve(n);
  t_gripper2base.reserve(n);
  R_target2cam.reserve(n);
  t_target2cam.reserve(n);
  for (size_t k = 0; k < n; ++k) {
    // gripper2base = M_k = ref0_from_master_k: p_ref0 = R p_master + C.
    const Pose& m = master_poses[k];
    R_gripper2base.push_back(ToCvRotation(m.q.normalized().toRotationMatrix()));
    t_gripper2base.push_back(ToCvVector(m.C));
    // target2cam = S_k^-1 = slave_k_from_ref1.
    const Pose s_inv = slave_poses[k].Inverse();
    R_target2cam.push_back(ToCvRotation(s_inv.q.normalized().toRotationMatrix()));
    t_target2cam.push_back(ToCvVector(s_inv.C));
  }
  cv::Mat R_cam2gripper, t_cam2gripper;
  try {
    cv::calibrateHandEye(R_gripper2base, t_gripper2base, R_target2cam, t_target2cam, R_cam2gripper,
                         t_cam2gripper, ToCv(method));
  } catch (const cv::Exception& e) {
    result.error = e.what();
    return result;
  }
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = R_cam2gripper.at<double>(r, c);
    t(r) = t_cam2gripper.at<double>(r);
  }
  if (!R.allFinite() || !t.allFinite()) {
    result.error = "non-finite result";
    return result;
  }
  result.master_from_slave.q = Eigen::Quaterniond(R).normalized();
  result.master_from_slave.C = t;
  result.master_from_slave.scale = 1.0;
  result.ok = true;
  return result;
}

std::vector<HandEyeResult> OpenCvHandEyeAll(const std::vector<Pose>& master_poses,
                                            const std::vector<Pose>& slave_poses) {
  std::vector<HandEyeResult> results;
  for (HandEyeMethod method : kAllHandEyeMethods) {
    results.push_back(OpenCvHandEye(master_poses, slave_poses, method));
  }
  return results;
}

void SubsampledPoses(const RigRecording& recording, int slave_index, int stride,
                     std::vector<Pose>* master_poses, std::vector<Pose>* slave_poses) {
  master_poses->clear();
  slave_poses->clear();
  if (stride < 1) stride = 1;
  const auto& slave = recording.slaves.at(static_cast<size_t>(slave_index)).poses;
  for (size_t k = 0; k < recording.master.poses.size() && k < slave.size();
       k += static_cast<size_t>(stride)) {
    master_poses->push_back(recording.master.poses[k]);
    slave_poses->push_back(slave[k]);
  }
}

}  // namespace rigcal::support
