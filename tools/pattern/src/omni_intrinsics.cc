// SPDX-License-Identifier: Apache-2.0
// Omnidirectional (unified / Mei) intrinsics through cv::omnidir.
#include "rigcal/pattern/omni_intrinsics.h"

#include <algorithm>
#include <cstdio>

#include "opencv.h"
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/ccalib/omnidir.hpp>
#pragma GCC diagnostic pop

namespace rigcal::pattern {

io::CamchainEntry OmniIntrinsics::ToCamchainEntry() const {
  io::CamchainEntry entry;
  entry.spec.name = camera;
  entry.spec.model = camera::CameraSpec::Model::kPinhole;
  entry.spec.width = width;
  entry.spec.height = height;
  entry.spec.intrinsics = intrinsics;
  entry.spec.distortion = {distortion[0], distortion[1], distortion[2], distortion[3]};
  entry.omni_xi = xi;
  return entry;
}

Expected<OmniIntrinsics> CalibrateOmni(const CameraViews& views, int max_views) {
  const size_t n = views.views.size();
  if (n < 4 || max_views < 4) {
    return Error{views.camera + ": " + std::to_string(n) +
                 " views with a target, the omnidirectional model needs at least 4"};
  }
  const size_t m = std::min(n, static_cast<size_t>(max_views));
  std::vector<cv::Mat> object;
  std::vector<cv::Mat> image;
  for (size_t i = 0; i < m; ++i) {
    const TargetView& v = views.views[m == n ? i : (i * (n - 1)) / (m - 1)];
    cv::Mat o(1, static_cast<int>(v.pixels.size()), CV_64FC3);
    cv::Mat p(1, static_cast<int>(v.pixels.size()), CV_64FC2);
    for (size_t j = 0; j < v.pixels.size(); ++j) {
      o.at<cv::Vec3d>(0, static_cast<int>(j)) =
          cv::Vec3d(v.target_points[j].x(), v.target_points[j].y(), v.target_points[j].z());
      p.at<cv::Vec2d>(0, static_cast<int>(j)) = cv::Vec2d(v.pixels[j].x(), v.pixels[j].y());
    }
    object.push_back(o);
    image.push_back(p);
  }
  cv::Mat K;
  cv::Mat xi;
  cv::Mat D;
  std::vector<cv::Mat> rvecs;
  std::vector<cv::Mat> tvecs;
  cv::Mat used;
  OmniIntrinsics out;
  try {
    out.rms_px = cv::omnidir::calibrate(
        object, image, cv::Size(views.width, views.height), K, xi, D, rvecs, tvecs,
        cv::omnidir::CALIB_FIX_SKEW,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 300, 1e-10), used);
  } catch (const cv::Exception& e) {
    return Error{views.camera + ": OpenCV omnidirectional calibration failed: " + e.what()};
  }
  out.camera = views.camera;
  out.width = views.width;
  out.height = views.height;
  out.views_given = static_cast<int>(m);
  out.views_used = static_cast<int>(used.total());
  if (out.views_used < 4) {
    return Error{views.camera + ": the omnidirectional calibration kept " +
                 std::to_string(out.views_used) + " of " + std::to_string(m) +
                 " views, need 4 (views that show the target from more directions help)"};
  }
  out.xi = xi.at<double>(0);
  out.intrinsics = {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2), K.at<double>(1, 2)};
  for (int i = 0; i < 4; ++i) out.distortion[static_cast<size_t>(i)] = D.at<double>(i);
  return out;
}

std::string FormatOmni(const OmniIntrinsics& o) {
  char line[400];
  std::snprintf(line, sizeof(line),
                "%s: omni %dx%d  xi %.5f fx %.3f fy %.3f cx %.3f cy %.3f  distortion [%.6g, "
                "%.6g, %.6g, %.6g]\n%s: RMS %.3f px over %d views (%d given)\n",
                o.camera.c_str(), o.width, o.height, o.xi, o.intrinsics[0], o.intrinsics[1],
                o.intrinsics[2], o.intrinsics[3], o.distortion[0], o.distortion[1], o.distortion[2],
                o.distortion[3], o.camera.c_str(), o.rms_px, o.views_used, o.views_given);
  return line;
}

}  // namespace rigcal::pattern
