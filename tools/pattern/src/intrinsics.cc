// SPDX-License-Identifier: Apache-2.0
// Intrinsic calibration with OpenCV (calibrateCamera, cv::fisheye::calibrate) or the polynomial
// omnidirectional model (polynomial_calibration.h), outlier views rejected by their RMS
// reprojection error.
#include "rigcal/pattern/intrinsics.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <sstream>

#include "intrinsics_uncertainty.h"
#include "opencv.h"
#include "polynomial_calibration.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/pattern/target_poses.h"

namespace rigcal::pattern {
namespace {

using camera::CameraSpec;

// Calibrates from the views at `indices`; fills spec's intrinsics and distortion.
Status Solve(const CameraViews& views, const std::vector<size_t>& indices, CameraSpec* spec,
             double* rms) {
  const cv::Size size(views.width, views.height);
  if (spec->model == CameraSpec::Model::kScaramuzza) {
    return internal::CalibratePolynomial(views, indices, spec, rms);
  }
  try {
    if (spec->model == CameraSpec::Model::kFisheye) {
      std::vector<std::vector<cv::Point3d>> object(indices.size());
      std::vector<std::vector<cv::Point2d>> image(indices.size());
      for (size_t i = 0; i < indices.size(); ++i) {
        const TargetView& v = views.views[indices[i]];
        for (size_t j = 0; j < v.pixels.size(); ++j) {
          object[i].emplace_back(v.target_points[j].x(), v.target_points[j].y(),
                                 v.target_points[j].z());
          image[i].emplace_back(v.pixels[j].x(), v.pixels[j].y());
        }
      }
      cv::Matx33d K;
      cv::Vec4d D;
      std::vector<cv::Mat> rvecs;
      std::vector<cv::Mat> tvecs;
      *rms = cv::fisheye::calibrate(
          object, image, size, K, D, rvecs, tvecs,
          cv::fisheye::CALIB_RECOMPUTE_EXTRINSIC | cv::fisheye::CALIB_FIX_SKEW,
          cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10));
      spec->intrinsics = {K(0, 0), K(1, 1), K(0, 2), K(1, 2)};
      spec->distortion = {D[0], D[1], D[2], D[3]};
    } else {
      std::vector<std::vector<cv::Point3f>> object;
      std::vector<std::vector<cv::Point2f>> image;
      for (size_t i : indices) {
        object.push_back(internal::ObjectPoints(views.views[i]));
        image.push_back(internal::ImagePoints(views.views[i]));
      }
      cv::Mat K;
      cv::Mat D;
      std::vector<cv::Mat> rvecs;
      std::vector<cv::Mat> tvecs;
      *rms = cv::calibrateCamera(
          object, image, size, K, D, rvecs, tvecs, cv::CALIB_FIX_K3,
          cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
      spec->intrinsics = {K.at<double>(0, 0), K.at<double>(1, 1), K.at<double>(0, 2),
                          K.at<double>(1, 2)};
      spec->distortion = {D.at<double>(0), D.at<double>(1), D.at<double>(2), D.at<double>(3)};
    }
  } catch (const cv::Exception& e) {
    return Error{views.camera + ": OpenCV calibration failed: " + e.what()};
  }
  return {};
}

}  // namespace

Status IntrinsicsOptions::Check() const {
  if (min_views < 3) return Error{"min_views: must be >= 3"};
  if (max_views < min_views) return Error{"max_views: must be >= min_views"};
  return {};
}

namespace {

// The views given to the solver: all, or max_views spread evenly.
std::vector<size_t> CandidateViews(size_t n, int max_views) {
  std::vector<size_t> candidates;
  const size_t m = std::min(n, static_cast<size_t>(max_views));
  for (size_t i = 0; i < m; ++i) candidates.push_back(m == n ? i : (i * (n - 1)) / (m - 1));
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  return candidates;
}

// Per-view RMS of the `used` views under `spec` (an unfitted view counts as the largest).
Expected<std::vector<double>> UsedViewRms(const CameraViews& views, const std::vector<size_t>& used,
                                          const CameraSpec& spec) {
  CameraViews subset;
  subset.camera = views.camera;
  subset.width = views.width;
  subset.height = views.height;
  for (size_t i : used) subset.views.push_back(views.views[i]);
  auto stats = EstimateTargetPoses(subset, spec, std::numeric_limits<double>::infinity());
  if (!stats) return Error{stats.error()};
  std::vector<double> view_rms;
  for (const ViewStatistics& v : *stats) {
    view_rms.push_back(std::isfinite(v.rms_px) ? v.rms_px : std::numeric_limits<double>::max());
  }
  return view_rms;
}

// Far above the others' spread and twice their median, and never under a hundredth of a
// pixel: sub-pixel corner detectors reach a few hundredths at best, so a view fitted better
// is not an outlier (on noiseless views the RMS is the solver's rounding or the model's
// own approximation, and its spread means nothing).
double RejectionThresholdPx(const std::vector<double>& view_rms) {
  const double median = Median(view_rms);
  std::vector<double> deviation;
  deviation.reserve(view_rms.size());
  for (double r : view_rms) deviation.push_back(std::abs(r - median));
  constexpr double kPerfectFitPx = 0.01;
  return std::max({median + 5.0 * 1.4826 * Median(deviation), 2.0 * median, kPerfectFitPx});
}

// The views used and rejected, the intrinsics fitted on the used ones, the last threshold.
struct FittedViews {
  CameraSpec spec;
  std::vector<size_t> used;
  std::vector<size_t> rejected;
  double threshold_px = std::numeric_limits<double>::quiet_NaN();
};

// Solves, then (options.reject_outliers) drops the views whose RMS is far above the others' and
// solves again, up to four rounds.
Status FitRejectingOutliers(const CameraViews& views, const IntrinsicsOptions& options,
                            FittedViews* fitted) {
  const auto log = ModuleLogger("target");
  double rms = 0.0;
  for (int round = 0; round < 4; ++round) {
    if (fitted->used.size() < static_cast<size_t>(options.min_views)) {
      return Error{views.camera + ": only " + std::to_string(fitted->used.size()) +
                   " views left after rejecting outliers, need " +
                   std::to_string(options.min_views)};
    }
    if (Status s = Solve(views, fitted->used, &fitted->spec, &rms); !s.ok()) return s;
    if (Status s = fitted->spec.Check(); !s.ok()) {
      return Error{views.camera +
                   ": the calibrated intrinsics are not a valid camera: " + s.message()};
    }
    if (!options.reject_outliers || round == 3) break;
    auto view_rms = UsedViewRms(views, fitted->used, fitted->spec);
    if (!view_rms) return Error{view_rms.error()};
    fitted->threshold_px = RejectionThresholdPx(*view_rms);
    std::vector<size_t> keep;
    for (size_t k = 0; k < fitted->used.size(); ++k) {
      if ((*view_rms)[k] <= fitted->threshold_px) {
        keep.push_back(fitted->used[k]);
      } else {
        fitted->rejected.push_back(fitted->used[k]);
        log->info("{}: view {} rejected: RMS {:.3f} px > {:.3f} px", views.camera,
                  views.views[fitted->used[k]].file, (*view_rms)[k], fitted->threshold_px);
      }
    }
    if (keep.size() == fitted->used.size()) break;
    fitted->used = std::move(keep);
  }
  return {};
}

// Every view's statistics under the fitted intrinsics, the RMS over the used views' corners and
// the parameters' σ.
Expected<IntrinsicsResult> ResultOf(const CameraViews& views, const FittedViews& fitted) {
  IntrinsicsResult result;
  result.spec = fitted.spec;
  result.rejection_threshold_px = fitted.threshold_px;
  auto stats = EstimateTargetPoses(views, fitted.spec, std::numeric_limits<double>::infinity());
  if (!stats) return Error{stats.error()};
  result.views = std::move(*stats);
  double sum_sq = 0.0;
  size_t points = 0;
  for (ViewStatistics& v : result.views) v.used = false;
  for (size_t i : fitted.used) {
    ViewStatistics& v = result.views[i];
    v.used = true;
    sum_sq += v.rms_px * v.rms_px * v.corners;
    points += static_cast<size_t>(v.corners);
  }
  for (size_t i : fitted.rejected) result.views[i].rejected = true;
  result.views_used = static_cast<int>(fitted.used.size());
  result.views_rejected = static_cast<int>(fitted.rejected.size());
  result.rms_px = points > 0 ? std::sqrt(sum_sq / static_cast<double>(points)) : 0.0;
  if (auto sigma = internal::ParameterStdDev(fitted.spec, views, result.views, fitted.used)) {
    result.parameter_names = internal::ParameterNames(fitted.spec);
    result.parameter_std = std::move(*sigma);
  } else {
    result.parameter_std_error = sigma.error();
    ModuleLogger("target")->debug("{}: parameter sigma unknown: {}", views.camera, sigma.error());
  }
  return result;
}

}  // namespace

Expected<IntrinsicsResult> CalibrateIntrinsics(const CameraViews& views,
                                               const IntrinsicsOptions& options) {
  if (Status s = options.Check(); !s.ok()) return Error{s.message()};
  const size_t n = views.views.size();
  if (n < static_cast<size_t>(options.min_views)) {
    return Error{views.camera + ": " + std::to_string(n) + " views with a target, need at least " +
                 std::to_string(options.min_views)};
  }
  FittedViews fitted;
  fitted.spec.name = views.camera;
  fitted.spec.model = options.model;
  fitted.spec.width = views.width;
  fitted.spec.height = views.height;
  fitted.used = CandidateViews(n, options.max_views);
  if (Status s = FitRejectingOutliers(views, options, &fitted); !s.ok()) {
    return Error{s.message()};
  }
  return ResultOf(views, fitted);
}

std::string FormatIntrinsics(const IntrinsicsResult& result, bool per_view) {
  std::ostringstream out;
  char line[512];
  const CameraSpec& s = result.spec;
  if (per_view) {
    std::snprintf(line, sizeof(line), "%-28s %7s %8s %8s  %s\n", "view", "corners", "rms_px",
                  "max_px", "");
    out << line;
    for (const ViewStatistics& v : result.views) {
      std::snprintf(line, sizeof(line), "%-28s %7d %8.3f %8.3f  %s\n", v.file.c_str(), v.corners,
                    v.rms_px, v.max_px,
                    v.rejected ? "rejected (outlier)"
                    : v.used   ? "used"
                               : "not used");
      out << line;
    }
  }
  const auto list = [](const double* values, size_t n) {
    std::string text;
    for (size_t i = 0; i < n; ++i) {
      char buf[32];
      std::snprintf(buf, sizeof(buf), "%s%.6g", i == 0 ? "" : ", ", values[i]);
      text += buf;
    }
    return text;
  };
  if (s.model == CameraSpec::Model::kScaramuzza) {
    std::snprintf(line, sizeof(line),
                  "%s: scaramuzza %dx%d  center %.3f %.3f  affine [%.6g, %.6g, %.6g]  poly [%s]\n",
                  s.name.c_str(), s.width, s.height, s.center[0], s.center[1], s.affine[0],
                  s.affine[1], s.affine[2], list(s.poly.data(), s.poly.size()).c_str());
  } else {
    std::snprintf(line, sizeof(line),
                  "%s: %s %dx%d  fx %.3f fy %.3f cx %.3f cy %.3f  distortion [%s]\n",
                  s.name.c_str(), std::string(camera::ModelName(s.model)).c_str(), s.width,
                  s.height, s.intrinsics[0], s.intrinsics[1], s.intrinsics[2], s.intrinsics[3],
                  list(s.distortion.data(), s.distortion.size()).c_str());
  }
  out << line;
  std::snprintf(line, sizeof(line),
                "%s: RMS %.3f px over %d views (%d rejected, threshold %.3f px, %zu views in "
                "all)\n",
                s.name.c_str(), result.rms_px, result.views_used, result.views_rejected,
                result.rejection_threshold_px, result.views.size());
  out << line;
  if (!result.parameter_std.empty()) {
    out << s.name << ": sigma";
    for (size_t i = 0; i < result.parameter_std.size(); ++i) {
      std::snprintf(line, sizeof(line), " %s %.3g", result.parameter_names[i].c_str(),
                    result.parameter_std[i]);
      out << line;
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace rigcal::pattern
