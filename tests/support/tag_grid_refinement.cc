// SPDX-License-Identifier: Apache-2.0
#include "support/tag_grid_refinement.h"

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "rigcal/base/robust_statistics.h"
#include "support/ceres_transform.h"
#include "support/pinhole_intrinsics.h"

namespace rigcal::support {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// A detected corner against the corner of the tag, through the tag's pose on the board and
// the camera's pose (camera from board).
struct CornerCost {
  Eigen::Vector3d corner_in_tag;
  Eigen::Vector2d corner_px;
  PinholeIntrinsics k;

  template <typename T>
  bool operator()(const T* q_cam_from_grid, const T* t_cam_from_grid, const T* q_grid_from_tag,
                  const T* t_grid_from_tag, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_cg(q_cam_from_grid), q_gt(q_grid_from_tag);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_cg(t_cam_from_grid), t_gt(t_grid_from_tag);
    const Eigen::Matrix<T, 3, 1> in_grid = q_gt * corner_in_tag.cast<T>() + t_gt;
    const Eigen::Matrix<T, 3, 1> p = q_cg * in_grid + t_cg;
    residual[0] = T(k.fx) * p.x() / p.z() + T(k.cx) - T(corner_px.x());
    residual[1] = T(k.fy) * p.y() / p.z() + T(k.cy) - T(corner_px.y());
    return true;
  }
};

// Each tag's pose on the board as the recording's poses imply it (grid_from_cam * cam_from_tag),
// averaged over the frames that saw it.
std::map<int, Pose> RecordedLayout(const RealMonoSequence& s) {
  std::map<int, Eigen::Vector4d> q_sum;
  std::map<int, Eigen::Vector3d> c_sum;
  std::map<int, int> seen;
  for (size_t f = 0; f < s.tag_from_cam.size(); ++f) {
    for (const auto& [id, tag_from_cam] : s.tag_from_cam[f]) {
      const Pose grid_from_tag = s.grid_from_cam[f] * tag_from_cam.Inverse();
      Eigen::Vector4d q = grid_from_tag.q.coeffs();
      auto& sum = q_sum.try_emplace(id, Eigen::Vector4d::Zero()).first->second;
      if (sum.dot(q) < 0.0) q = -q;
      sum += q;
      c_sum.try_emplace(id, Eigen::Vector3d::Zero()).first->second += grid_from_tag.C;
      ++seen[id];
    }
  }
  std::map<int, Pose> layout;
  for (const auto& [id, n] : seen) {
    Pose p;
    p.q = Eigen::Quaterniond(q_sum[id].normalized());
    p.C = c_sum[id] / n;
    layout[id] = p;
  }
  return layout;
}

struct Problem {
  std::vector<CeresTransform> cam_from_grid;  // per frame
  std::map<int, CeresTransform> grid_from_tag;
};

void Solve(const RealMonoSequence& s, const PinholeIntrinsics& k, double huber_px, int fixed_tag,
           Problem* p) {
  ceres::Problem problem;
  const auto in_tag = s.TagCornersInTag();
  for (size_t f = 0; f < s.tag_corners_px.size(); ++f) {
    CeresTransform& cam = p->cam_from_grid[f];
    for (const auto& [id, corners] : s.tag_corners_px[f]) {
      CeresTransform& tag = p->grid_from_tag.at(id);
      for (int c = 0; c < 4; ++c) {
        auto* cost = new ceres::AutoDiffCostFunction<CornerCost, 2, 4, 3, 4, 3>(
            new CornerCost{in_tag[c], corners[c], k});
        problem.AddResidualBlock(cost, new ceres::HuberLoss(huber_px), cam.q.data(), cam.t.data(),
                                 tag.q.data(), tag.t.data());
      }
    }
    if (problem.HasParameterBlock(cam.q.data())) {
      problem.SetManifold(cam.q.data(), new ceres::EigenQuaternionManifold);
    }
  }
  for (auto& [id, tag] : p->grid_from_tag) {
    if (!problem.HasParameterBlock(tag.q.data())) continue;
    problem.SetManifold(tag.q.data(), new ceres::EigenQuaternionManifold);
    if (id == fixed_tag) {
      problem.SetParameterBlockConstant(tag.q.data());
      problem.SetParameterBlockConstant(tag.t.data());
    }
  }
  SolveAdjustment(&problem);
}

// Every corner's residual (x and y) and the RMS per frame at the solution.
std::vector<double> Residuals(const RealMonoSequence& s, const PinholeIntrinsics& k,
                              const Problem& p, std::vector<double>* rms_px) {
  std::vector<double> all;
  const auto in_tag = s.TagCornersInTag();
  rms_px->assign(s.tag_corners_px.size(), 0.0);
  for (size_t f = 0; f < s.tag_corners_px.size(); ++f) {
    double sum2 = 0.0;
    int n = 0;
    for (const auto& [id, corners] : s.tag_corners_px[f]) {
      const CeresTransform& tag = p.grid_from_tag.at(id);
      for (int c = 0; c < 4; ++c) {
        const CornerCost cost{in_tag[c], corners[c], k};
        double r[2];
        cost(p.cam_from_grid[f].q.data(), p.cam_from_grid[f].t.data(), tag.q.data(), tag.t.data(),
             r);
        all.push_back(r[0]);
        all.push_back(r[1]);
        sum2 += r[0] * r[0] + r[1] * r[1];
        ++n;
      }
    }
    (*rms_px)[f] = n > 0 ? std::sqrt(sum2 / n) : 0.0;
  }
  return all;
}

// 1.4826 times the median absolute residual: the σ of zero-mean Gaussian residuals, robust to
// the outliers among them.
double RobustSigma(std::vector<double> residuals) {
  for (double& r : residuals) r = std::abs(r);
  return 1.4826 * Median(std::move(residuals));
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The Cramér-Rao σ of frame f's rotation about the camera's axes, the layout held fixed: the
// pose perturbed as p -> exp(δθ) p + δt in the camera frame, information Σ JᵀJ / σ².
Eigen::Vector3d RotationSigmaDeg(const RealMonoSequence& s, const PinholeIntrinsics& k,
                                 const Problem& p, size_t f, double sigma_px) {
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  const auto in_tag = s.TagCornersInTag();
  const CeresTransform& cam = p.cam_from_grid[f];
  for (const auto& [id, corners] : s.tag_corners_px[f]) {
    const CeresTransform& tag = p.grid_from_tag.at(id);
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector3d x = cam.Q() * (tag.Q() * in_tag[c] + tag.T()) + cam.T();
      Eigen::Matrix<double, 2, 3> d_projection;
      d_projection << k.fx / x.z(), 0.0, -k.fx * x.x() / (x.z() * x.z()), 0.0, k.fy / x.z(),
          -k.fy * x.y() / (x.z() * x.z());
      Eigen::Matrix<double, 3, 6> d_point;
      d_point << -Skew(x), Eigen::Matrix3d::Identity();
      const Eigen::Matrix<double, 2, 6> j = d_projection * d_point;
      information += j.transpose() * j;
    }
  }
  const Eigen::Matrix<double, 6, 6> covariance =
      (information / (sigma_px * sigma_px)).ldlt().solve(Eigen::Matrix<double, 6, 6>::Identity());
  return covariance.diagonal().head<3>().cwiseSqrt() * kRadToDeg;
}

}  // namespace

Expected<RefinedTagGrid> RefineTagGrid(const RealMonoSequence& s) {
  if (s.tag_corners_px.empty() || s.tag_corners_px.size() != s.grid_from_cam.size()) {
    return Error{s.name + ": no tag detections to refine"};
  }
  auto pinhole = PinholeOf(*s.camera);
  if (!pinhole) return Error{s.name + ": RefineTagGrid " + pinhole.error()};
  const PinholeIntrinsics k = *pinhole;

  Problem p;
  const std::map<int, Pose> recorded = RecordedLayout(s);
  int fixed_tag = -1, most_seen = 0;
  std::map<int, int> seen;
  for (const auto& frame : s.tag_corners_px) {
    for (const auto& [id, corners] : frame) {
      if (++seen[id] > most_seen) most_seen = seen[id], fixed_tag = id;
    }
  }
  for (const auto& [id, pose] : recorded) p.grid_from_tag[id] = CeresTransform::FromPose(pose);
  for (const Pose& grid_from_cam : s.grid_from_cam) {
    p.cam_from_grid.push_back(CeresTransform::FromPose(grid_from_cam.Inverse()));
  }
  for (const auto& [id, n] : seen) {
    if (p.grid_from_tag.count(id) == 0) {
      return Error{s.name + ": tag " + std::to_string(id) + " has corners but no pose"};
    }
  }

  // A first solve with a 1 px Huber scale, then again with the Huber scale at 1.345 σ of the
  // residuals it leaves (95 % efficiency on Gaussian corner noise).
  Solve(s, k, 1.0, fixed_tag, &p);
  RefinedTagGrid out;
  out.corner_sigma_px = RobustSigma(Residuals(s, k, p, &out.residual_rms_px));
  Solve(s, k, 1.345 * out.corner_sigma_px, fixed_tag, &p);
  out.corner_sigma_px = RobustSigma(Residuals(s, k, p, &out.residual_rms_px));
  out.recorded_residual_rms_px = TagGridResidualsPx(s);

  for (size_t f = 0; f < p.cam_from_grid.size(); ++f) {
    out.grid_from_cam.push_back(p.cam_from_grid[f].ToPose().Inverse());
    out.rotation_sigma_deg.push_back(RotationSigmaDeg(s, k, p, f, out.corner_sigma_px));
  }
  for (const auto& [id, tag] : p.grid_from_tag) {
    out.grid_from_tag[id] = tag.ToPose();
  }
  return out;
}

}  // namespace rigcal::support
