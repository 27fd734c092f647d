// SPDX-License-Identifier: Apache-2.0
// MonocularVo set-up: the lens's valid image area, field of view and feature budget.

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "monocular_vo_impl.h"

namespace rigcal::vo {

MonocularVo::Impl::Impl(std::shared_ptr<const camera::CameraModel> camera, int camera_index,
                        VoOptions options)
    : options_(options),
      camera_(std::move(camera)),
      camera_index_(camera_index),
      rolling_shutter_(camera_ != nullptr ? camera_->rolling_shutter_s() : 0.0,
                       camera_ != nullptr ? camera_->height() : 0),
      exposure_(options.inlier_sigmas, options.noise_window_frames),
      noise_(options.noise_floor_px, options.inlier_sigmas, options.noise_window_frames) {
  RequireValid(options_.Check(), "VoOptions");
  describer_ = std::make_unique<OrbDescriber>(options_.relocalisation_features);
  log_ = ModuleLogger("vo");
  max_tracks_ = options_.max_features;
  rng_.seed(options_.seed);
  KltOptions klt;
  klt.window_px = options_.klt_window_px;
  klt.pyramid_levels = options_.klt_pyramid_levels;
  klt.max_fb_error_px = options_.klt_max_fb_error_px;
  klt_ = KltTracker(klt);
  if (camera_ == nullptr) {
    log_->error("camera {}: no camera model; every frame will be rejected", camera_index_);
    return;
  }
  pixel_angle_ = camera_->PixelAngle();
  if (!(pixel_angle_ > 0.0) || !std::isfinite(pixel_angle_)) pixel_angle_ = 1e-3;

  // Valid area: pixels that unproject within the field of view (sampled every 4 pixels).
  const int w = camera_->width();
  const int h = camera_->height();
  const int step = 4;
  const double max_angle = camera_->MaxFieldAngleDeg() * kDegToRad;
  cv::Mat coarse((h + step - 1) / step, (w + step - 1) / step, CV_8UC1);
  for (int y = 0; y < coarse.rows; ++y) {
    for (int x = 0; x < coarse.cols; ++x) {
      const Eigen::Vector2d px(std::min(x * step + step / 2, w - 1),
                               std::min(y * step + step / 2, h - 1));
      const auto f = camera_->Unproject(px);
      bool ok = f.has_value() &&
                std::acos(std::clamp(f->normalized().z(), -1.0, 1.0)) <= max_angle + 1e-9;
      if (ok) {
        const auto back = camera_->Project(*f);
        ok = back.has_value() && (*back - px).norm() < 1.0;
      }
      coarse.at<unsigned char>(y, x) = ok ? 255 : 0;
    }
  }
  cv::resize(coarse, valid_mask_, cv::Size(coarse.cols * step, coarse.rows * step), 0, 0,
             cv::INTER_NEAREST);
  valid_mask_ = valid_mask_(cv::Rect(0, 0, w, h)).clone();
  cv::Mat detect_mask;
  const int border = std::max(1, options_.border_px);
  cv::erode(valid_mask_, detect_mask,
            cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * border + 1, 2 * border + 1)));

  // Field of view: the share of directions (a Fibonacci sphere) that land in the valid area.
  constexpr int kDirections = 4000;
  int seen = 0;
  for (int i = 0; i < kDirections; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / kDirections;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = i * M_PI * (3.0 - std::sqrt(5.0));  // golden angle
    const Eigen::Vector3d d(r * std::cos(phi), r * std::sin(phi), z);
    if (std::acos(std::clamp(z, -1.0, 1.0)) > max_angle + 1e-9) continue;
    const auto px = camera_->Project(d);
    if (px && InMask(cv::Point2f(static_cast<float>(px->x()), static_cast<float>(px->y())))) {
      ++seen;
    }
  }
  fov_sr_ = 4.0 * M_PI * seen / kDirections;
  // Wide lenses track more features, on cells small enough to hold them.
  int cell_px = options_.grid_cell_px;
  if (options_.normal_fov_sr > 0.0 && fov_sr_ > options_.normal_fov_sr) {
    max_tracks_ =
        static_cast<int>(std::lround(options_.max_features * fov_sr_ / options_.normal_fov_sr));
    const double area = cv::countNonZero(detect_mask);
    cell_px = std::clamp(static_cast<int>(std::sqrt(area / max_tracks_)), 4, cell_px);
  }
  log_->debug("camera {}: field of view {:.2f} sr, up to {} features on {} px cells", camera_index_,
              fov_sr_, max_tracks_, cell_px);
  grid_ = std::make_unique<FeatureGrid>(cv::Size(w, h), cell_px, options_.fast_threshold,
                                        options_.border_px, detect_mask);
}

bool MonocularVo::Impl::InMask(const cv::Point2f& px) const {
  const int x = static_cast<int>(std::lround(px.x));
  const int y = static_cast<int>(std::lround(px.y));
  if (x < 0 || y < 0 || x >= valid_mask_.cols || y >= valid_mask_.rows) return false;
  return valid_mask_.at<unsigned char>(y, x) != 0;
}

double MonocularVo::Impl::NoiseRad() const { return noise_.sigma_px() * pixel_angle_; }

double MonocularVo::Impl::PoseGateRad() const { return options_.inlier_sigmas * NoiseRad(); }

double MonocularVo::Impl::PairGateRad() const { return std::sqrt(2.0) * PoseGateRad(); }

double MonocularVo::Impl::HuberRad() const { return options_.huber_sigmas * NoiseRad(); }

bool MonocularVo::Impl::Unproject(const cv::Point2f& px, Eigen::Vector3d* bearing) const {
  const auto f = camera_->Unproject(Eigen::Vector2d(px.x, px.y));
  if (!f.has_value() || !f->allFinite()) return false;
  const double norm = f->norm();
  if (!(norm > 0.0)) return false;
  *bearing = *f / norm;
  return true;
}

}  // namespace rigcal::vo
