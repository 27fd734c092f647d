// SPDX-License-Identifier: Apache-2.0
// MonocularVo: the public object and the per-frame dispatch (image checks, initialisation,
// tracking or relocalisation by state). The stages are in monocular_vo_*.cc, the state in
// monocular_vo_impl.h.

#include "rigcal/vo/monocular_vo.h"

#include <algorithm>
#include <chrono>
#include <opencv2/imgproc.hpp>
#include <string>

#include "monocular_vo_impl.h"

namespace rigcal::vo {

CameraPose MonocularVo::Impl::MakePose(int64_t t_ns, const CameraPoseRC& pose,
                                       double quality) const {
  CameraPose out;
  out.camera = camera_index_;
  out.t_ns = t_ns;
  out.segment = segment_;
  out.pose.q = Eigen::Quaterniond(pose.R_world_from_cam).normalized();
  out.pose.C = pose.C;
  out.quality = std::clamp(quality, 0.0, 1.0);
  return out;
}

VoResult MonocularVo::Impl::Process(int64_t t_ns, const cv::Mat& image) {
  const auto start = std::chrono::steady_clock::now();
  // Before anything else: the state is then the one the last keyframe left.
  FinishKeyframeWork();
  VoResult result;
  ++frames_;
  cv::Mat grey;
  std::string problem;
  if (camera_ == nullptr) {
    problem = "no camera model";
  } else if (image.empty()) {
    problem = "empty image";
  } else if (image.cols != camera_->width() || image.rows != camera_->height()) {
    problem = "image is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
              ", camera model is " + std::to_string(camera_->width()) + "x" +
              std::to_string(camera_->height());
  } else if (image.type() == CV_8UC1) {
    grey = image;
  } else if (image.type() == CV_8UC3) {
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  } else if (image.type() == CV_8UC4) {
    cv::cvtColor(image, grey, cv::COLOR_BGRA2GRAY);
  } else {
    problem = "unsupported image type " + std::to_string(image.type());
  }

  if (!problem.empty()) {
    // A frame without usable pixels: tracking cannot continue across it.
    klt_.Reset();
    if (state_ == VoState::kTracking) {
      Lose(problem, t_ns, cv::Mat(), &result);
    } else if (state_ == VoState::kLost) {
      Relocalise(t_ns, cv::Mat(), &result);
    } else {
      tracks_.clear();
      has_reference_ = false;
      result.state = state_;
    }
    result.message = problem;
  } else {
    // Exposure steps scaled back: the tracked patches keep their grey levels.
    const cv::Mat tracked = exposure_.Apply(grey);
    klt_.AddImage(tracked);
    if (state_ == VoState::kTracking) {
      TrackFrame(t_ns, tracked, &result);
    } else if (state_ == VoState::kLost) {
      Relocalise(t_ns, tracked, &result);
    } else {
      Initialise(t_ns, tracked, &result);
    }
  }
  result.tracked_features = static_cast<int>(tracks_.size());
  result.relocalisations = relocalisations_;
  result.track_noise_px = noise_.sigma_px();
  result.processing_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  log_->debug("camera {} frame {}: {} tracks {} inliers {} kf {} {:.2f} ms {}", camera_index_,
              frames_, ToString(result.state), result.tracked_features, result.inliers,
              result.keyframe, result.processing_ms, result.message);
  return result;
}

MonocularVo::MonocularVo(std::shared_ptr<const camera::CameraModel> camera, int camera_index,
                         VoOptions options)
    : impl_(std::make_unique<Impl>(std::move(camera), camera_index, options)) {}
MonocularVo::~MonocularVo() = default;
MonocularVo::MonocularVo(MonocularVo&&) noexcept = default;
MonocularVo& MonocularVo::operator=(MonocularVo&&) noexcept = default;

VoResult MonocularVo::Process(int64_t t_ns, const cv::Mat& grey) {
  return impl_->Process(t_ns, grey);
}
VoState MonocularVo::state() const { return impl_->state_; }
int MonocularVo::segment() const { return impl_->segment_; }
int64_t MonocularVo::frames_processed() const { return impl_->frames_; }
int MonocularVo::relocalisations() const { return impl_->relocalisations_; }
const VoOptions& MonocularVo::options() const { return impl_->options_; }
double MonocularVo::field_of_view_sr() const { return impl_->fov_sr_; }
int MonocularVo::feature_budget() const { return impl_->max_tracks_; }

}  // namespace rigcal::vo
