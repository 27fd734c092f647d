// SPDX-License-Identifier: Apache-2.0
// Thesis 5.1.2 and 5.1.3: stability of the linear (LLS) and non-linear (NL) calibration against
// the pose orientation error level and against the number of poses (figures 5.1-5.4).
#include <string>

#include "rigcal/research/experiments.h"

namespace rigcal::research {
namespace {

constexpr uint64_t kStabilityStream = 1;
constexpr uint64_t kPosesStream = 2;

std::vector<CalibrationOptions> LlsAndNl() {
  return {ThesisCalibrationOptions(Method::kLinear, MotionModel::kGeneral, ScaleModel::kFixed),
          ThesisCalibrationOptions(Method::kNonlinear, MotionModel::kGeneral, ScaleModel::kFixed)};
}

// `degenerate`: bound geometries skipped because the poses do not determine the parameters.
void AddCommonNotes(const ExperimentOptions& options, int degenerate, ExperimentResult* result) {
  result->notes.push_back(
      "calibrator: series lls = Method::kLinear, nl = Method::kNonlinear (refines the linear "
      "estimate); motion_model = general, scale_model = fixed, pairs = since start (0, k), "
      "alpha_threshold_deg = 0, outlier_mad_factor = 1e9 (misfit removal off), robust loss none: "
      "every motion is used, as in the thesis");
  result->notes.push_back("generator: ThesisSample (thesis 5.1.2), one slave, " +
                          std::to_string(options.samples) + " samples per point, seed " +
                          std::to_string(options.seed) + "; lls and nl on the same samples");
  result->notes.push_back(
      "errors: *_mean = mean of the absolute errors of thesis 5.1.1 over the solved estimates "
      "(what the thesis plots), *_rms = root mean square, *_median = median (robust to rare gross "
      "failures); failed = samples without an estimate");
  if (options.crb_samples > 0) {
    result->notes.push_back(
        "crb_*: Cramer-Rao bound of the linear-Gaussian model (rotation noise per-axis sigma "
        "eps/sqrt(3), position noise |C| eps/sqrt(3) per axis perpendicular to C, lengths exact; "
        "the thesis noise has this covariance), RMS over " +
        std::to_string(options.crb_samples) +
        " geometries at eps = 1 deg, scaled linearly to each eps (the bound is linear in eps). "
        "It bounds the RMS error: compare it with the *_rms columns; the means of absolute "
        "errors (*_mean, plotted by the thesis) are smaller than RMS values" +
        (degenerate > 0 ? "; " + std::to_string(degenerate) + " degenerate geometries skipped"
                        : std::string()));
  }
}

}  // namespace

ExperimentResult RunStability(const ExperimentOptions& options) {
  ExperimentResult result = NewExperimentResult(ExperimentKind::kStability, options);
  if (!result.error.empty()) return result;

  std::vector<ThesisSampleOptions> points;
  for (double eps : options.stability_eps_deg) {
    ThesisSampleOptions point;
    point.num_poses = options.num_poses;
    point.eps_deg = eps;
    points.push_back(point);
  }
  const auto stats = RunGrid(points, LlsAndNl(), options, kStabilityStream);
  const BoundStats bound = AverageThesisBound(options.num_poses, options);

  const char* series[] = {"lls", "nl"};
  for (int v = 0; v < 2; ++v) {
    for (size_t p = 0; p < points.size(); ++p) {
      ExperimentRow row;
      row.series = series[v];
      row.eps_deg = points[p].eps_deg;
      row.num_poses = options.num_poses;
      row.errors = stats[p][v];
      row.crb = bound.Scaled(points[p].eps_deg);
      result.rows.push_back(row);
    }
  }
  AddCommonNotes(options, bound.degenerate, &result);
  return result;
}

ExperimentResult RunPoses(const ExperimentOptions& options) {
  ExperimentResult result = NewExperimentResult(ExperimentKind::kPoses, options);
  if (!result.error.empty()) return result;

  std::vector<ThesisSampleOptions> points;
  std::vector<BoundStats> bounds;
  int degenerate = 0;
  for (int k = options.poses_min; k <= options.poses_max; ++k) {
    ThesisSampleOptions point;
    point.num_poses = k;
    point.eps_deg = options.poses_eps_deg;
    points.push_back(point);
    bounds.push_back(AverageThesisBound(k, options).Scaled(options.poses_eps_deg));
    degenerate += bounds.back().degenerate;
  }
  const auto stats = RunGrid(points, LlsAndNl(), options, kPosesStream);

  const char* series[] = {"lls", "nl"};
  for (int v = 0; v < 2; ++v) {
    for (size_t p = 0; p < points.size(); ++p) {
      ExperimentRow row;
      row.series = series[v];
      row.eps_deg = points[p].eps_deg;
      row.num_poses = points[p].num_poses;
      row.errors = stats[p][v];
      row.crb = bounds[p];
      result.rows.push_back(row);
    }
  }
  AddCommonNotes(options, degenerate, &result);
  return result;
}

}  // namespace rigcal::research
