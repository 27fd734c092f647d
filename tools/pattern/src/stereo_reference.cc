// SPDX-License-Identifier: Apache-2.0
// The stereoCalibrate reference: both cameras' target views jointly, intrinsics fixed.
#include <map>
#include <tuple>

#include "opencv.h"
#include "rigcal/pattern/reference_calibration.h"

namespace rigcal::pattern {
namespace {

using Key = std::tuple<long long, long long, long long>;

// Target coordinates rounded to 1e-6 of their unit, to match corners across cameras.
Key PointKey(const Eigen::Vector3d& p) {
  return {std::llround(p.x() * 1e6), std::llround(p.y() * 1e6), std::llround(p.z() * 1e6)};
}

cv::Matx33d CameraMatrix(const camera::CameraSpec& s) {
  return cv::Matx33d(s.intrinsics[0], 0.0, s.intrinsics[2], 0.0, s.intrinsics[1], s.intrinsics[3],
                     0.0, 0.0, 1.0);
}

cv::Mat Distortion(const camera::CameraSpec& s) {
  cv::Mat d = cv::Mat::zeros(5, 1, CV_64F);
  for (size_t i = 0; i < s.distortion.size() && i < 5; ++i) {
    d.at<double>(static_cast<int>(i)) = s.distortion[i];
  }
  return d;
}

}  // namespace

Expected<ReferenceEstimate> EstimateStereoReference(const CameraViews& master,
                                                    const camera::CameraSpec& master_spec,
                                                    const CameraViews& slave,
                                                    const camera::CameraSpec& slave_spec,
                                                    double* rms_px) {
  if (master_spec.model != camera::CameraSpec::Model::kPinhole ||
      slave_spec.model != camera::CameraSpec::Model::kPinhole) {
    return Error{"stereo reference: pinhole cameras only"};
  }
  std::map<int64_t, const TargetView*> slave_views;
  for (const TargetView& v : slave.views) slave_views.emplace(v.t_ns, &v);
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image0;
  std::vector<std::vector<cv::Point2f>> image1;
  for (const TargetView& v0 : master.views) {
    const auto it = slave_views.find(v0.t_ns);
    if (it == slave_views.end()) continue;
    const TargetView& v1 = *it->second;
    std::map<Key, size_t> index1;
    for (size_t j = 0; j < v1.target_points.size(); ++j)
      index1.emplace(PointKey(v1.target_points[j]), j);
    std::vector<cv::Point3f> obj;
    std::vector<cv::Point2f> p0;
    std::vector<cv::Point2f> p1;
    for (size_t j = 0; j < v0.target_points.size(); ++j) {
      const auto m = index1.find(PointKey(v0.target_points[j]));
      if (m == index1.end()) continue;
      const Eigen::Vector3d& X = v0.target_points[j];
      obj.emplace_back(float(X.x()), float(X.y()), float(X.z()));
      p0.emplace_back(float(v0.pixels[j].x()), float(v0.pixels[j].y()));
      p1.emplace_back(float(v1.pixels[m->second].x()), float(v1.pixels[m->second].y()));
    }
    if (obj.size() < 8) continue;
    object.push_back(std::move(obj));
    image0.push_back(std::move(p0));
    image1.push_back(std::move(p1));
  }
  if (object.size() < 3) {
    return Error{"stereo reference: " + std::to_string(object.size()) + " views shared by " +
                 master.camera + " and " + slave.camera + ", need 3"};
  }
  cv::Mat K0(CameraMatrix(master_spec));
  cv::Mat K1(CameraMatrix(slave_spec));
  cv::Mat D0 = Distortion(master_spec);
  cv::Mat D1 = Distortion(slave_spec);
  cv::Mat R;
  cv::Mat T;
  cv::Mat E;
  cv::Mat F;
  double rms = 0.0;
  try {
    rms = cv::stereoCalibrate(
        object, image0, image1, K0, D0, K1, D1, cv::Size(master.width, master.height), R, T, E, F,
        cv::CALIB_FIX_INTRINSIC,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10));
  } catch (const cv::Exception& e) {
    return Error{std::string("stereo reference: OpenCV stereoCalibrate failed: ") + e.what()};
  }
  if (rms_px != nullptr) *rms_px = rms;
  // R, T map master points to slave points: slave_from_master. The slave in the master frame:
  // q = R^T, C = -R^T T.
  Eigen::Matrix3d slave_from_master;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) slave_from_master(r, c) = R.at<double>(r, c);
  }
  const Eigen::Vector3d t(T.at<double>(0), T.at<double>(1), T.at<double>(2));
  ReferenceEstimate out;
  out.slave = slave.camera;
  out.master_from_slave.q = Eigen::Quaterniond(slave_from_master.transpose()).normalized();
  out.master_from_slave.C = -slave_from_master.transpose() * t;
  out.master_from_slave.scale = 1.0;
  out.instants = static_cast<int>(object.size());
  return out;
}

}  // namespace rigcal::pattern
