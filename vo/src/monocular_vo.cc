#include "rigcal/vo/monocular_vo.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>
#include <sstream>
#include <unordered_set>

#include "absolute_pose.h"
#include "affine_patch.h"
#include "feature_grid.h"
#include "klt_tracker.h"
#include "local_bundle_adjustment.h"
#include "relative_pose.h"
#include "rigcal/calib/logging.h"
#include "triangulation.h"
#include "vo_map.h"

namespace rigcal::vo {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// One KLT feature track.
struct Track {
  cv::Point2f px;
  Eigen::Vector3d bearing = Eigen::Vector3d::UnitZ();  // current frame, unit, camera frame
  int landmark = -1;                                   // map point, -1 = none yet
  // Where the track was born: a keyframe (tracking) or the reference frame (initialising,
  // anchor_keyframe = -1), and its bearing there (for triangulation and parallax).
  int anchor_keyframe = -1;
  Eigen::Vector3d anchor_bearing = Eigen::Vector3d::UnitZ();
  // Reference patch (affine refinement) and its current warp into the image; null: none.
  std::shared_ptr<const PatchTemplate> patch;
  Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + mid, v.end());
  return v[mid];
}

double Angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Frame-to-frame motion of two poses (previous^-1 * current) and its application.
CameraPoseRC Between(const CameraPoseRC& a, const CameraPoseRC& b) {
  CameraPoseRC d;
  d.R_world_from_cam = a.R_world_from_cam.transpose() * b.R_world_from_cam;
  d.C = a.R_world_from_cam.transpose() * (b.C - a.C);
  return d;
}

CameraPoseRC Compose(const CameraPoseRC& a, const CameraPoseRC& d) {
  CameraPoseRC out;
  out.R_world_from_cam = a.R_world_from_cam * d.R_world_from_cam;
  out.C = a.C + a.R_world_from_cam * d.C;
  return out;
}

}  // namespace

bool VoOptions::Check(std::string* error) const {
  std::ostringstream e;
  auto require = [&](bool ok, const char* field, const char* constraint) {
    if (!ok) e << "VoOptions." << field << " must be " << constraint << "; ";
  };
  require(grid_cell_px >= 4, "grid_cell_px", ">= 4");
  require(max_features >= 20, "max_features", ">= 20");
  require(normal_fov_sr >= 0.0 && normal_fov_sr <= 4.0 * M_PI, "normal_fov_sr",
          "in [0, 4 pi] (0: max_features for every lens)");
  require(fast_threshold >= 1 && fast_threshold <= 255, "fast_threshold", "in [1, 255]");
  require(klt_window_px >= 5 && klt_window_px % 2 == 1, "klt_window_px", "odd and >= 5");
  require(klt_pyramid_levels >= 0 && klt_pyramid_levels <= 8, "klt_pyramid_levels", "in [0, 8]");
  require(klt_max_fb_error_px > 0.0, "klt_max_fb_error_px", "> 0");
  require(border_px >= 0, "border_px", ">= 0");
  require(affine_half_size >= 0 && affine_half_size <= 15, "affine_half_size", "in [0, 15]");
  require(affine_max_shift_px > 0.0, "affine_max_shift_px", "> 0");
  require(affine_min_area > 0.0 && affine_min_area < 1.0, "affine_min_area", "in (0, 1)");
  require(affine_max_area > 1.0, "affine_max_area", "> 1");
  require(ransac_threshold_px > 0.0, "ransac_threshold_px", "> 0");
  require(ransac_max_iterations >= 1, "ransac_max_iterations", ">= 1");
  require(ransac_confidence > 0.0 && ransac_confidence < 1.0, "ransac_confidence", "in (0, 1)");
  require(min_init_tracks >= 8, "min_init_tracks", ">= 8");
  require(min_init_inliers >= 8, "min_init_inliers", ">= 8");
  require(min_init_parallax_deg > 0.0, "min_init_parallax_deg", "> 0");
  require(min_init_rotation_residual_px > 0.0, "min_init_rotation_residual_px", "> 0");
  require(min_init_cheirality_fraction > 0.0 && min_init_cheirality_fraction <= 1.0,
          "min_init_cheirality_fraction", "in (0, 1]");
  require(min_tracking_inliers >= 4, "min_tracking_inliers", ">= 4");
  require(min_inlier_ratio >= 0.0 && min_inlier_ratio <= 1.0, "min_inlier_ratio", "in [0, 1]");
  require(min_triangulation_angle_deg > 0.0, "min_triangulation_angle_deg", "> 0");
  require(keyframe_track_ratio > 0.0 && keyframe_track_ratio <= 1.0, "keyframe_track_ratio",
          "in (0, 1]");
  require(keyframe_parallax_deg > 0.0, "keyframe_parallax_deg", "> 0");
  require(keyframe_max_frames >= 1, "keyframe_max_frames", ">= 1");
  require(ba_window >= 3, "ba_window", ">= 3");
  require(ba_max_iterations >= 0, "ba_max_iterations", ">= 0");
  require(ba_huber_px > 0.0, "ba_huber_px", "> 0");
  const std::string message = e.str();
  if (error != nullptr) *error = message;
  return message.empty();
}

std::string ToString(VoState state) {
  switch (state) {
    case VoState::kInitialising:
      return "initialising";
    case VoState::kTracking:
      return "tracking";
    case VoState::kLost:
      return "lost";
  }
  return "unknown";
}

class MonocularVo::Impl {
 public:
  Impl(std::shared_ptr<const camera::CameraModel> camera, int camera_index, VoOptions options);
  VoResult Process(int64_t t_ns, const cv::Mat& image);

  VoState state_ = VoState::kInitialising;
  int segment_ = 0;
  int64_t frames_ = 0;
  VoOptions options_;
  double fov_sr_ = 0.0;  // solid angle of the valid image area
  int max_tracks_ = 0;   // feature budget for this lens

 private:
  void StartReference(int64_t t_ns, const cv::Mat& grey);
  void TrackFeatures(const cv::Mat& grey, const CameraPoseRC* predicted);
  // Refines the KLT position of `track` by aligning its reference patch (affine) in `grey`;
  // renews the patch where it cannot be aligned or has deformed too much.
  void RefineTrack(const cv::Mat& grey, Track* track) const;
  std::shared_ptr<const PatchTemplate> MakePatch(const cv::Mat& grey, const cv::Point2f& px) const;
  void Initialise(int64_t t_ns, const cv::Mat& grey, VoResult* result);
  void TrackFrame(int64_t t_ns, const cv::Mat& grey, VoResult* result);
  void CreateKeyframe(int64_t t_ns, const cv::Mat& grey);
  void AddNewTracks(const cv::Mat& grey, int anchor_keyframe);
  void Lose(const std::string& reason, int64_t t_ns, const cv::Mat& grey, VoResult* result);
  void UnlinkRemovedLandmarks();
  CameraPose MakePose(int64_t t_ns, const CameraPoseRC& pose, double quality) const;
  bool Unproject(const cv::Point2f& px, Eigen::Vector3d* bearing) const;
  bool InMask(const cv::Point2f& px) const;

  std::shared_ptr<const camera::CameraModel> camera_;
  int camera_index_ = 0;
  std::shared_ptr<spdlog::logger> log_;
  double pixel_angle_ = 1e-3;
  cv::Mat valid_mask_;  // CV_8UC1: where tracks may live
  KltTracker klt_;
  std::unique_ptr<FeatureGrid> grid_;
  std::mt19937 rng_;

  std::vector<Track> tracks_;
  int next_segment_ = 0;

  // Initialisation.
  bool has_reference_ = false;
  int64_t reference_t_ns_ = 0;

  // Tracking.
  VoMap map_;
  CameraPoseRC pose_;
  CameraPoseRC velocity_;  // last frame-to-frame motion
  bool has_velocity_ = false;
  int last_keyframe_ = -1;
  int frames_since_keyframe_ = 0;
  int keyframe_landmarks_ = 0;
};

MonocularVo::Impl::Impl(std::shared_ptr<const camera::CameraModel> camera, int camera_index,
                        VoOptions options)
    : options_(options), camera_(std::move(camera)), camera_index_(camera_index) {
  log_ = ModuleLogger("vo");
  std::string error;
  if (!options_.Check(&error)) {
    log_->error("camera {}: invalid VO options ({}); using the defaults", camera_index_, error);
    options_ = VoOptions{};
  }
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

bool MonocularVo::Impl::Unproject(const cv::Point2f& px, Eigen::Vector3d* bearing) const {
  const auto f = camera_->Unproject(Eigen::Vector2d(px.x, px.y));
  if (!f.has_value() || !f->allFinite()) return false;
  const double norm = f->norm();
  if (!(norm > 0.0)) return false;
  *bearing = *f / norm;
  return true;
}

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
    } else {
      tracks_.clear();
      has_reference_ = false;
      result.state = state_;
      result.message = problem;
    }
  } else {
    klt_.AddImage(grey);
    if (state_ == VoState::kTracking) {
      TrackFrame(t_ns, grey, &result);
    } else {
      Initialise(t_ns, grey, &result);
    }
  }
  result.tracked_features = static_cast<int>(tracks_.size());
  result.processing_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  log_->debug("camera {} frame {}: {} tracks {} inliers {} kf {} {:.2f} ms {}", camera_index_,
              frames_, ToString(result.state), result.tracked_features, result.inliers,
              result.keyframe, result.processing_ms, result.message);
  return result;
}

void MonocularVo::Impl::AddNewTracks(const cv::Mat& grey, int anchor_keyframe) {
  const int room = max_tracks_ - static_cast<int>(tracks_.size());
  if (room <= 0) return;
  std::vector<cv::Point2f> existing;
  existing.reserve(tracks_.size());
  for (const Track& t : tracks_) existing.push_back(t.px);
  for (const cv::Point2f& px : grid_->Detect(grey, existing, room)) {
    Track t;
    t.px = px;
    if (!Unproject(px, &t.bearing)) continue;
    t.patch = MakePatch(grey, px);
    t.anchor_keyframe = anchor_keyframe;
    t.anchor_bearing = t.bearing;
    tracks_.push_back(t);
  }
}

void MonocularVo::Impl::StartReference(int64_t t_ns, const cv::Mat& grey) {
  tracks_.clear();
  has_reference_ = false;
  if (grey.empty()) return;
  AddNewTracks(grey, -1);
  if (static_cast<int>(tracks_.size()) >= options_.min_init_tracks) {
    has_reference_ = true;
    reference_t_ns_ = t_ns;
    state_ = VoState::kInitialising;
  } else {
    tracks_.clear();
  }
}

std::shared_ptr<const PatchTemplate> MonocularVo::Impl::MakePatch(const cv::Mat& grey,
                                                                  const cv::Point2f& px) const {
  if (options_.affine_half_size <= 0) return nullptr;
  auto patch = std::make_shared<PatchTemplate>();
  if (!MakePatchTemplate(grey, px, options_.affine_half_size, patch.get())) return nullptr;
  return patch;
}

void MonocularVo::Impl::RefineTrack(const cv::Mat& grey, Track* track) const {
  if (options_.affine_half_size <= 0) return;
  if (track->patch != nullptr) {
    AffinePatchOptions affine;
    affine.half_size = options_.affine_half_size;
    Eigen::Matrix2d warp = track->warp;
    Eigen::Vector2d centre(track->px.x, track->px.y);
    if (AlignPatch(*track->patch, grey, affine, &warp, &centre) &&
        (centre - Eigen::Vector2d(track->px.x, track->px.y)).norm() <=
            options_.affine_max_shift_px) {
      track->px = cv::Point2f(static_cast<float>(centre.x()), static_cast<float>(centre.y()));
      track->warp = warp;
      // Keep the reference close to the current view: the patch is sampled anew once it
      // appears at a very different size or shape.
      const double area = warp.determinant();
      const double shear = (warp / std::sqrt(std::abs(area)) - Eigen::Matrix2d::Identity()).norm();
      if (area > options_.affine_min_area && area < 1.0 / options_.affine_min_area && shear < 0.4) {
        return;
      }
    }
  }
  track->patch = MakePatch(grey, track->px);
  track->warp.setIdentity();
}

void MonocularVo::Impl::TrackFeatures(const cv::Mat& grey, const CameraPoseRC* predicted) {
  std::vector<cv::Point2f> previous, guesses, tracked;
  std::vector<unsigned char> ok;
  previous.reserve(tracks_.size());
  for (const Track& t : tracks_) previous.push_back(t.px);
  guesses = previous;
  if (predicted != nullptr) {
    const Eigen::Matrix3d rt = predicted->R_world_from_cam.transpose();
    for (size_t i = 0; i < tracks_.size(); ++i) {
      const Landmark* lm = tracks_[i].landmark >= 0 ? map_.landmark(tracks_[i].landmark) : nullptr;
      if (lm == nullptr) continue;
      const auto px = camera_->Project(rt * (lm->point - predicted->C));
      if (px.has_value() && px->allFinite()) {
        const cv::Point2f guess(static_cast<float>(px->x()), static_cast<float>(px->y()));
        if (InMask(guess)) guesses[i] = guess;
      }
    }
  }
  klt_.Track(previous, guesses, &tracked, &ok);
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!ok[i] || !InMask(tracked[i])) continue;
    Track t = tracks_[i];
    t.px = tracked[i];
    RefineTrack(grey, &t);
    if (!InMask(t.px) || !Unproject(t.px, &t.bearing)) continue;
    kept.push_back(t);
  }
  tracks_.swap(kept);
}

void MonocularVo::Impl::Initialise(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  result->state = state_;
  if (!has_reference_ || !klt_.has_previous()) {
    StartReference(t_ns, grey);
    result->state = state_;
    result->message = has_reference_ ? "reference frame set" : "too few features";
    return;
  }
  TrackFeatures(grey, nullptr);
  if (static_cast<int>(tracks_.size()) < options_.min_init_tracks) {
    StartReference(t_ns, grey);
    result->state = state_;
    result->message = "too few tracks to the reference frame; reference renewed";
    return;
  }

  const double threshold = options_.ransac_threshold_px * pixel_angle_;
  const double min_parallax = options_.min_init_parallax_deg * kDegToRad;
  std::vector<Eigen::Vector3d> f_ref, f_cur;
  f_ref.reserve(tracks_.size());
  f_cur.reserve(tracks_.size());
  for (const Track& t : tracks_) {
    f_ref.push_back(t.anchor_bearing);
    f_cur.push_back(t.bearing);
  }
  // Cheap test first: when a pure rotation explains the tracks to within a few pixels there is
  // no parallax to initialise from, whatever an essential matrix would say (with a pure
  // rotation every translation fits the epipolar constraint).
  auto rotation_residual = [&](const std::vector<char>* mask) {
    std::vector<Eigen::Vector3d> a, b;
    for (size_t i = 0; i < f_ref.size(); ++i) {
      if (mask != nullptr && !(*mask)[i]) continue;
      a.push_back(f_ref[i]);
      b.push_back(f_cur[i]);
    }
    const Eigen::Matrix3d r = BestRotation(a, b);
    std::vector<double> residual;
    residual.reserve(a.size());
    for (size_t i = 0; i < a.size(); ++i) residual.push_back(Angle(a[i], r * b[i]));
    return Median(residual);
  };
  const double min_rotation_residual = options_.min_init_rotation_residual_px * pixel_angle_;
  if (rotation_residual(nullptr) < min_rotation_residual) {
    result->message = "insufficient parallax (rotation only)";
    return;
  }

  RelativePoseRansacOptions ransac;
  ransac.max_epipolar_angle_rad = threshold;
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.min_init_inliers;
  const RelativePoseRansacResult rel = EstimateRelativePose(f_ref, f_cur, ransac, &rng_);
  result->inliers = rel.num_inliers;
  if (!rel.success || rel.num_inliers < options_.min_init_inliers) {
    result->message = "essential matrix: too few inliers";
    return;
  }
  if (rel.num_in_front < options_.min_init_cheirality_fraction * rel.num_inliers) {
    result->message = "essential matrix: degenerate geometry (points behind the cameras)";
    return;
  }
  if (rotation_residual(&rel.inliers) < min_rotation_residual) {
    result->message = "insufficient parallax (rotation only)";
    return;
  }
  // Parallax: median angle between the rays of the inliers once the rotation is removed.
  std::vector<double> parallax;
  for (size_t i = 0; i < f_ref.size(); ++i) {
    if (rel.inliers[i]) parallax.push_back(Angle(f_ref[i], rel.pose.R_1_from_2 * f_cur[i]));
  }
  const double median_parallax = Median(parallax);
  if (median_parallax < min_parallax) {
    result->message = "insufficient parallax";
    return;
  }

  // Triangulate the inliers in the reference frame, ||C^1|| = 1.
  const Eigen::Matrix3d& r1 = rel.pose.R_1_from_2;
  const Eigen::Vector3d c1 = rel.pose.C2_in_1.normalized();
  const double min_angle = options_.min_triangulation_angle_deg * kDegToRad;
  std::vector<std::pair<size_t, Eigen::Vector3d>> points;
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!rel.inliers[i]) continue;
    const auto tri = TriangulateMidpoint(Eigen::Vector3d::Zero(), f_ref[i], c1, r1 * f_cur[i]);
    if (!tri || tri->ray_angle_rad < min_angle) continue;
    if (BearingAngle(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero(), f_ref[i], tri->point) >
            2.0 * threshold ||
        BearingAngle(r1, c1, f_cur[i], tri->point) > 2.0 * threshold) {
      continue;
    }
    points.emplace_back(i, tri->point);
  }
  if (static_cast<int>(points.size()) < options_.min_init_inliers) {
    result->message = "too few triangulated points";
    return;
  }

  map_.Clear();
  const int kf0 =
      map_.AddKeyframe(reference_t_ns_, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  const int kf1 = map_.AddKeyframe(t_ns, Eigen::Quaterniond(r1), c1);
  for (Track& t : tracks_) t.anchor_keyframe = kf0;
  for (const auto& [i, point] : points) {
    const int lm = map_.AddLandmark(point);
    map_.AddObservation(lm, kf0, f_ref[i]);
    map_.AddObservation(lm, kf1, f_cur[i]);
    tracks_[i].landmark = lm;
  }
  LocalBaOptions ba;
  ba.num_fixed = 1;
  ba.unit_baseline = true;
  ba.max_iterations = std::max(10, options_.ba_max_iterations);
  ba.huber_rad = options_.ba_huber_px * pixel_angle_;
  ba.outlier_rad = 3.0 * threshold;
  LocalBundleAdjust({kf0, kf1}, ba, &map_);
  UnlinkRemovedLandmarks();
  const Keyframe* k1 = map_.keyframe(kf1);
  pose_.R_world_from_cam = k1->R();
  pose_.C = k1->C;
  has_velocity_ = false;
  last_keyframe_ = kf1;
  frames_since_keyframe_ = 0;
  keyframe_landmarks_ = 0;
  for (const Track& t : tracks_) keyframe_landmarks_ += t.landmark >= 0;
  if (keyframe_landmarks_ < options_.min_init_inliers / 2) {
    map_.Clear();
    for (Track& t : tracks_) {
      t.landmark = -1;
      t.anchor_keyframe = -1;
    }
    result->message = "initial bundle adjustment rejected the points";
    return;
  }
  AddNewTracks(grey, kf1);

  segment_ = next_segment_++;
  state_ = VoState::kTracking;
  const double quality = std::min(1.0, static_cast<double>(keyframe_landmarks_) / 100.0);
  result->state = state_;
  result->keyframe = true;
  result->message.clear();
  result->pose = MakePose(t_ns, pose_, quality);
  result->segment_start = MakePose(reference_t_ns_, CameraPoseRC{}, 1.0);
  log_->info("camera {}: initialised segment {} ({} points, {} inliers, parallax {:.2f} deg)",
             camera_index_, segment_, keyframe_landmarks_, rel.num_inliers,
             median_parallax / kDegToRad);
}

void MonocularVo::Impl::UnlinkRemovedLandmarks() {
  for (Track& t : tracks_) {
    if (t.landmark >= 0 && map_.landmark(t.landmark) == nullptr) t.landmark = -1;
  }
}

void MonocularVo::Impl::Lose(const std::string& reason, int64_t t_ns, const cv::Mat& grey,
                             VoResult* result) {
  log_->warn("camera {}: tracking lost in segment {}: {}", camera_index_, segment_, reason);
  map_.Clear();
  tracks_.clear();
  has_velocity_ = false;
  has_reference_ = false;
  state_ = VoState::kLost;
  // The frame may still be good (e.g. a sudden motion): start the next reference from it.
  if (!grey.empty()) StartReference(t_ns, grey);
  if (!has_reference_) state_ = VoState::kLost;
  result->state = VoState::kLost;
  result->message = reason;
}

void MonocularVo::Impl::TrackFrame(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  const CameraPoseRC predicted = has_velocity_ ? Compose(pose_, velocity_) : pose_;
  TrackFeatures(grey, &predicted);
  ++frames_since_keyframe_;

  std::vector<int> index;
  std::vector<Eigen::Vector3d> f, X;
  for (int i = 0; i < static_cast<int>(tracks_.size()); ++i) {
    const Landmark* lm = tracks_[i].landmark >= 0 ? map_.landmark(tracks_[i].landmark) : nullptr;
    if (lm == nullptr) continue;
    index.push_back(i);
    f.push_back(tracks_[i].bearing);
    X.push_back(lm->point);
  }
  if (static_cast<int>(f.size()) < options_.min_tracking_inliers) {
    Lose("too few tracked map points (" + std::to_string(f.size()) + ")", t_ns, grey, result);
    return;
  }
  const double threshold = options_.ransac_threshold_px * pixel_angle_;
  PnpRansacOptions ransac;
  ransac.max_angle_rad = threshold;
  ransac.max_iterations = options_.ransac_max_iterations;
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.min_tracking_inliers;
  PnpRansacResult pnp = EstimateAbsolutePose(f, X, ransac, &predicted, &rng_);
  const double ratio = pnp.success ? static_cast<double>(pnp.num_inliers) / f.size() : 0.0;
  if (!pnp.success || ratio < options_.min_inlier_ratio) {
    Lose("PnP: too few inliers (" + std::to_string(pnp.num_inliers) + " of " +
             std::to_string(f.size()) + ")",
         t_ns, grey, result);
    return;
  }
  CameraPoseRC pose = pnp.pose;
  if (!RefineAbsolutePose(f, X, pnp.inliers, options_.ba_huber_px * pixel_angle_, 10, &pose) ||
      !pose.R_world_from_cam.allFinite() || !pose.C.allFinite()) {
    Lose("PnP refinement failed (degenerate geometry)", t_ns, grey, result);
    return;
  }
  // Final inliers; outlier tracks are dropped (KLT drift or a bad point).
  std::vector<char> drop(tracks_.size(), 0);
  int inliers = 0;
  std::vector<double> parallax;
  const Keyframe* last_kf = map_.keyframe(last_keyframe_);
  for (size_t k = 0; k < f.size(); ++k) {
    if (AngularResidual(pose, f[k], X[k]) > threshold) {
      drop[index[k]] = 1;
      continue;
    }
    ++inliers;
    if (last_kf != nullptr) parallax.push_back(Angle(X[k] - last_kf->C, X[k] - pose.C));
  }
  if (inliers < options_.min_tracking_inliers) {
    Lose("too few inliers after refinement (" + std::to_string(inliers) + ")", t_ns, grey, result);
    return;
  }
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!drop[i]) kept.push_back(tracks_[i]);
  }
  tracks_.swap(kept);

  velocity_ = Between(pose_, pose);
  has_velocity_ = true;
  pose_ = pose;

  // Keyframe decision.
  const double median_parallax = Median(parallax);
  const double kf_parallax = options_.keyframe_parallax_deg * kDegToRad;
  const bool need_keyframe = inliers < options_.keyframe_track_ratio * keyframe_landmarks_ ||
                             median_parallax >= kf_parallax ||
                             (frames_since_keyframe_ >= options_.keyframe_max_frames &&
                              median_parallax >= 0.5 * kf_parallax) ||
                             inliers < 2 * options_.min_tracking_inliers;
  if (need_keyframe) {
    CreateKeyframe(t_ns, grey);
    result->keyframe = true;
  }
  result->state = state_;
  result->inliers = inliers;
  const double quality = ratio * std::min(1.0, inliers / 100.0);
  result->pose = MakePose(t_ns, pose_, quality);
}

void MonocularVo::Impl::CreateKeyframe(int64_t t_ns, const cv::Mat& grey) {
  const int kf = map_.AddKeyframe(t_ns, Eigen::Quaterniond(pose_.R_world_from_cam), pose_.C);
  const double threshold = options_.ransac_threshold_px * pixel_angle_;
  const double min_angle = options_.min_triangulation_angle_deg * kDegToRad;
  const Eigen::Matrix3d r = pose_.R_world_from_cam;
  for (Track& t : tracks_) {
    if (t.landmark >= 0 && map_.landmark(t.landmark) != nullptr) {
      map_.AddObservation(t.landmark, kf, t.bearing);
      continue;
    }
    t.landmark = -1;
    const Keyframe* anchor = map_.keyframe(t.anchor_keyframe);
    if (anchor == nullptr) {  // the anchor left the window: restart the track's baseline here
      t.anchor_keyframe = kf;
      t.anchor_bearing = t.bearing;
      continue;
    }
    const Eigen::Matrix3d ra = anchor->R();
    const auto tri = TriangulateMidpoint(anchor->C, ra * t.anchor_bearing, pose_.C, r * t.bearing);
    if (!tri || tri->ray_angle_rad < min_angle) continue;
    if (BearingAngle(ra, anchor->C, t.anchor_bearing, tri->point) > 2.0 * threshold ||
        BearingAngle(r, pose_.C, t.bearing, tri->point) > 2.0 * threshold) {
      continue;
    }
    const int lm = map_.AddLandmark(tri->point);
    map_.AddObservation(lm, t.anchor_keyframe, t.anchor_bearing);
    map_.AddObservation(lm, kf, t.bearing);
    t.landmark = lm;
  }

  const std::vector<int> window = map_.NewestKeyframes(options_.ba_window);
  LocalBaOptions ba;
  ba.num_fixed = std::min<int>(2, static_cast<int>(window.size()) - 1);
  ba.max_iterations = options_.ba_max_iterations;
  ba.huber_rad = options_.ba_huber_px * pixel_angle_;
  ba.outlier_rad = 3.0 * threshold;
  if (ba.max_iterations > 0) {
    const LocalBaSummary summary = LocalBundleAdjust(window, ba, &map_);
    if (summary.success) {
      const Keyframe* k = map_.keyframe(kf);
      pose_.R_world_from_cam = k->R();
      pose_.C = k->C;
    }
    UnlinkRemovedLandmarks();
  }

  std::unordered_set<int> alive;
  for (const Track& t : tracks_) {
    if (t.landmark >= 0) alive.insert(t.landmark);
  }
  map_.PruneKeyframes(options_.ba_window, [&](int id) { return alive.count(id) > 0; });
  for (Track& t : tracks_) {
    if (map_.keyframe(t.anchor_keyframe) == nullptr) {
      t.anchor_keyframe = kf;
      t.anchor_bearing = t.bearing;
    }
  }
  AddNewTracks(grey, kf);
  last_keyframe_ = kf;
  frames_since_keyframe_ = 0;
  keyframe_landmarks_ = 0;
  for (const Track& t : tracks_) keyframe_landmarks_ += t.landmark >= 0;
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
const VoOptions& MonocularVo::options() const { return impl_->options_; }
double MonocularVo::field_of_view_sr() const { return impl_->fov_sr_; }
int MonocularVo::feature_budget() const { return impl_->max_tracks_; }

}  // namespace rigcal::vo
