// SPDX-License-Identifier: Apache-2.0
#include "homography.h"

#include <Eigen/Dense>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "triangulation.h"

namespace rigcal::vo {
namespace {

// Bearings farther than this from the optical axis take no part in the homography: their
// normalised coordinates grow as tan(angle), which would let them dominate its fit.
const double kMaxFieldCos = std::cos(80.0 * M_PI / 180.0);

cv::Point2d Normalised(const Eigen::Vector3d& f) { return {f.x() / f.z(), f.y() / f.z()}; }

// Inliers of H by transfer angle (bearings off the plane's image never count).
int CountInliers(const std::vector<Eigen::Vector3d>& f1, const std::vector<Eigen::Vector3d>& f2,
                 const Eigen::Matrix3d& h, double max_angle_rad, std::vector<char>* inliers) {
  const Eigen::Matrix3d h_inverse = h.inverse();
  int count = 0;
  for (size_t i = 0; i < f1.size(); ++i) {
    const bool usable = f1[i].z() > kMaxFieldCos && f2[i].z() > kMaxFieldCos;
    (*inliers)[i] = usable && HomographyTransferAngle(h, h_inverse, f1[i], f2[i]) <= max_angle_rad;
    count += (*inliers)[i];
  }
  return count;
}

}  // namespace

double HomographyTransferAngle(const Eigen::Matrix3d& h, const Eigen::Matrix3d& h_inverse,
                               const Eigen::Vector3d& f1, const Eigen::Vector3d& f2) {
  // VectorAngle is scale-free but not sign-free: a bearing mapped behind is a gross error.
  return std::max(VectorAngle(f1, h * f2), VectorAngle(f2, h_inverse * f1));
}

HomographyRansacResult EstimateHomography(const std::vector<Eigen::Vector3d>& f1,
                                          const std::vector<Eigen::Vector3d>& f2,
                                          const HomographyRansacOptions& options) {
  HomographyRansacResult result;
  const size_t n = std::min(f1.size(), f2.size());
  std::vector<cv::Point2d> src, dst;  // view 2 -> view 1
  for (size_t i = 0; i < n; ++i) {
    if (f1[i].z() <= kMaxFieldCos || f2[i].z() <= kMaxFieldCos) continue;
    src.push_back(Normalised(f2[i]));
    dst.push_back(Normalised(f1[i]));
  }
  if (src.size() < 4) return result;
  // RANSAC on the transfer into view 1 (normalised coordinates: within the angular threshold at
  // the image centre, tighter off it; the final inliers are judged by angle).
  const cv::Mat h_ransac =
      cv::findHomography(src, dst, cv::RANSAC, options.max_transfer_angle_rad, cv::noArray(),
                         options.max_iterations, options.confidence);
  if (h_ransac.empty()) return result;
  Eigen::Matrix3d h;
  cv::cv2eigen(h_ransac, h);
  result.inliers.assign(n, 0);
  result.num_inliers = CountInliers(f1, f2, h, options.max_transfer_angle_rad, &result.inliers);
  // Least squares on the angular inliers (OpenCV's DLT and Levenberg-Marquardt), then the final
  // inlier set.
  src.clear();
  dst.clear();
  for (size_t i = 0; i < n; ++i) {
    if (!result.inliers[i]) continue;
    src.push_back(Normalised(f2[i]));
    dst.push_back(Normalised(f1[i]));
  }
  if (src.size() >= 8) {
    const cv::Mat h_fit = cv::findHomography(src, dst, 0);
    if (!h_fit.empty()) {
      Eigen::Matrix3d refined;
      cv::cv2eigen(h_fit, refined);
      std::vector<char> refined_inliers(n, 0);
      const int count =
          CountInliers(f1, f2, refined, options.max_transfer_angle_rad, &refined_inliers);
      if (count >= result.num_inliers) {
        h = refined;
        result.inliers.swap(refined_inliers);
        result.num_inliers = count;
      }
    }
  }
  // The scale that maps bearings in front to bearings in front: f1 . H f2 > 0 for inliers.
  double sign = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (result.inliers[i]) sign += f1[i].dot(h * f2[i]);
  }
  result.H_1_from_2 = sign < 0.0 ? Eigen::Matrix3d(-h) : h;
  result.success = h.allFinite();
  return result;
}

std::vector<PlanarMotion> DecomposeHomography(const Eigen::Matrix3d& H_1_from_2) {
  cv::Mat h;
  cv::eigen2cv(H_1_from_2, h);
  std::vector<cv::Mat> rotations, translations, normals;
  // OpenCV: x_dst ~ H x_src with X_dst = R X_src + t and n in the source view, so with view 2 as
  // the source R = R_1_from_2, t = C2_in_1 / d and n = n_in_2.
  cv::decomposeHomographyMat(h, cv::Matx33d::eye(), rotations, translations, normals);
  std::vector<PlanarMotion> out;
  for (size_t k = 0; k < rotations.size(); ++k) {
    PlanarMotion m;
    Eigen::Vector3d t, normal;
    cv::cv2eigen(rotations[k], m.pose.R_1_from_2);
    cv::cv2eigen(translations[k], t);
    cv::cv2eigen(normals[k], normal);
    m.baseline_over_distance = t.norm();
    m.pose.C2_in_1 = t.norm() > 0.0 ? Eigen::Vector3d(t.normalized()) : Eigen::Vector3d::Zero();
    m.normal_in_2 = normal.normalized();
    if (m.pose.R_1_from_2.allFinite() && m.pose.C2_in_1.allFinite()) out.push_back(m);
  }
  return out;
}

}  // namespace rigcal::vo
