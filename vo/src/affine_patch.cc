// SPDX-License-Identifier: Apache-2.0
#include "affine_patch.h"

#include <Eigen/Dense>
#include <cmath>

namespace rigcal::vo {
namespace {

// Bilinear sample of a CV_8UC1 image; false outside [0, cols - 1) x [0, rows - 1).
inline bool Sample(const cv::Mat& grey, double x, double y, float* value) {
  if (!(x >= 0.0 && y >= 0.0 && x < grey.cols - 1 && y < grey.rows - 1)) return false;
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float ax = static_cast<float>(x - x0);
  const float ay = static_cast<float>(y - y0);
  const uint8_t* row0 = grey.ptr<uint8_t>(y0) + x0;
  const uint8_t* row1 = row0 + grey.step[0];
  const float top = row0[0] + ax * (row0[1] - row0[0]);
  const float bottom = row1[0] + ax * (row1[1] - row1[0]);
  *value = top + ay * (bottom - top);
  return true;
}

}  // namespace

bool MakePatchTemplate(const cv::Mat& grey, const cv::Point2f& centre, int half_size,
                       PatchTemplate* patch) {
  patch->valid = false;
  patch->half_size = half_size;
  const int n = 2 * half_size + 1;
  const int m = n + 2;  // with a one-pixel ring for the gradients
  std::vector<float> grid(static_cast<size_t>(m) * m);
  for (int v = 0; v < m; ++v) {
    for (int u = 0; u < m; ++u) {
      if (!Sample(grey, centre.x + u - half_size - 1, centre.y + v - half_size - 1,
                  &grid[static_cast<size_t>(v) * m + u])) {
        return false;
      }
    }
  }
  patch->values.resize(static_cast<size_t>(n) * n);
  patch->sd.resize(static_cast<size_t>(n) * n * PatchTemplate::kSdStride);
  // The Gauss-Newton Hessian over the padded rows (float products, double sums): whole SIMD
  // registers, the same sums as over the 7 parameters alone; its last row and column are zero.
  constexpr int kStride = PatchTemplate::kSdStride;
  Eigen::Matrix<double, kStride, kStride> padded_hessian =
      Eigen::Matrix<double, kStride, kStride>::Zero();
  for (int v = 0; v < n; ++v) {
    for (int u = 0; u < n; ++u) {
      const size_t g = static_cast<size_t>(v + 1) * m + (u + 1);
      const float gx = 0.5f * (grid[g + 1] - grid[g - 1]);
      const float gy = 0.5f * (grid[g + m] - grid[g - m]);
      const float x = static_cast<float>(u - half_size);
      const float y = static_cast<float>(v - half_size);
      const size_t k = static_cast<size_t>(v) * n + u;
      patch->values[k] = grid[g];
      float* sd = &patch->sd[kStride * k];
      sd[0] = gx * x;
      sd[1] = gx * y;
      sd[2] = gy * x;
      sd[3] = gy * y;
      sd[4] = gx;
      sd[5] = gy;
      sd[6] = 1.f;
      sd[7] = 0.f;
      Eigen::Map<const Eigen::Matrix<float, kStride, 1>> j(sd);
      padded_hessian.noalias() += (j * j.transpose()).cast<double>();
    }
  }
  const Eigen::Matrix<double, 7, 7> hessian = padded_hessian.topLeftCorner<7, 7>();
  // Texture enough for the translation (the structure tensor) and the whole warp.
  const Eigen::Matrix2d tensor = hessian.block<2, 2>(4, 4) / (n * n);
  const double min_gradient =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(tensor).eigenvalues()(0);
  if (!(min_gradient > 4.0)) return false;  // (grey levels / px)^2: a flat or edge-only patch
  Eigen::LDLT<Eigen::Matrix<double, 7, 7>> ldlt(hessian);
  if (ldlt.info() != Eigen::Success ||
      !(ldlt.vectorD().minCoeff() > 1e-9 * ldlt.vectorD().maxCoeff())) {
    return false;
  }
  patch->inverse_hessian = ldlt.solve(Eigen::Matrix<double, 7, 7>::Identity());
  patch->valid = patch->inverse_hessian.allFinite();
  return patch->valid;
}

bool AlignPatch(const PatchTemplate& patch, const cv::Mat& grey, const AffinePatchOptions& options,
                Eigen::Matrix2d* warp, Eigen::Vector2d* centre, double* rms) {
  if (!patch.valid) return false;
  const int h = patch.half_size;
  const int n = 2 * h + 1;
  double offset = 0.0;
  double sum2 = 0.0;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const Eigen::Matrix2d& a = *warp;
    // The warped patch is a parallelogram: inside the image when its four corners are.
    for (const double cu : {-h, h}) {
      for (const double cv : {-h, h}) {
        const double x = centre->x() + a(0, 0) * cu + a(0, 1) * cv;
        const double y = centre->y() + a(1, 0) * cu + a(1, 1) * cv;
        if (!(x >= 0.0 && y >= 0.0 && x < grey.cols - 1 && y < grey.rows - 1)) return false;
      }
    }
    constexpr int kStride = PatchTemplate::kSdStride;
    Eigen::Matrix<float, kStride, 1> g = Eigen::Matrix<float, kStride, 1>::Zero();
    float sum2_f = 0.f;
    const float step_x = static_cast<float>(a(0, 0)), step_y = static_cast<float>(a(1, 0));
    const float offset_f = static_cast<float>(offset);
    for (int v = 0; v < n; ++v) {
      const double y = v - h;
      // Row start and step of the warped coordinates.
      float px = static_cast<float>(centre->x() + a(0, 0) * (-h) + a(0, 1) * y);
      float py = static_cast<float>(centre->y() + a(1, 0) * (-h) + a(1, 1) * y);
      const float* values = &patch.values[static_cast<size_t>(v) * n];
      const float* sd = &patch.sd[static_cast<size_t>(v) * n * kStride];
      for (int u = 0; u < n; ++u, px += step_x, py += step_y, sd += kStride) {
        const int x0 = static_cast<int>(px);
        const int y0 = static_cast<int>(py);
        const float ax = px - static_cast<float>(x0);
        const float ay = py - static_cast<float>(y0);
        const uint8_t* row0 = grey.ptr<uint8_t>(y0) + x0;
        const uint8_t* row1 = row0 + grey.step[0];
        const float top = row0[0] + ax * static_cast<float>(row0[1] - row0[0]);
        const float bottom = row1[0] + ax * static_cast<float>(row1[1] - row1[0]);
        const float e = top + ay * (bottom - top) - values[u] - offset_f;
        sum2_f += e * e;
        // Lane by lane the same float products and sums as one parameter at a time.
        g += Eigen::Map<const Eigen::Matrix<float, kStride, 1>>(sd) * e;
      }
    }
    sum2 = sum2_f;
    const Eigen::Matrix<double, 7, 1> dq = patch.inverse_hessian * g.head<7>().cast<double>();
    Eigen::Matrix2d increment;
    increment << 1.0 + dq[0], dq[1], dq[2], 1.0 + dq[3];
    const double det = increment.determinant();
    if (!(std::abs(det) > 1e-6)) return false;
    const Eigen::Matrix2d new_warp = (*warp) * increment.inverse();
    const Eigen::Vector2d new_centre = *centre - new_warp * Eigen::Vector2d(dq[4], dq[5]);
    const double step = (new_centre - *centre).norm();
    *warp = new_warp;
    *centre = new_centre;
    offset += dq[6];
    if (!warp->allFinite() || !centre->allFinite()) return false;
    const double area = warp->determinant();
    if (!(area > 1.0 / options.max_area_ratio && area < options.max_area_ratio)) return false;
    if (step < options.min_step_px) break;
  }
  const double residual = std::sqrt(sum2 / (n * n));
  if (rms != nullptr) *rms = residual;
  return residual <= options.max_rms;
}

}  // namespace rigcal::vo
