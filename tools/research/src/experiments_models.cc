// SPDX-License-Identifier: Apache-2.0
// Thesis 5.2 and 5.3: general vs purely translational motion model (figure 5.5) and time-fixed
// vs time-dependent scale model (figure 5.6), with their equal-error boundaries.
#include <cmath>
#include <functional>
#include <string>

#include "rigcal/research/experiments.h"

namespace rigcal::research {
namespace {

constexpr uint64_t kMotionModelStream = 3;
constexpr uint64_t kScaleModelStream = 4;

// The alternative model is better at a grid point when its mean error is lower (by more than
// rounding noise) and it failed at most 1 % of the samples more often than the simple model.
bool AlternativeBetter(const ErrorStats& simple, const ErrorStats& alternative, int samples,
                       const std::function<double(const ErrorStats&)>& metric) {
  const double a = metric(alternative);
  const double s = metric(simple);
  if (!std::isfinite(a)) return false;
  if (alternative.failed > simple.failed + 0.01 * samples) return false;
  // Errors below 1e-9 (deg) are rounding noise of exact solutions: a tie, not a win.
  constexpr double kTie = 1e-9;
  return !std::isfinite(s) || a + kTie < s;
}

// Smallest swept value from which on (to the end of the grid) the alternative model is better.
double Boundary(const std::vector<double>& values, const std::vector<bool>& better) {
  double boundary = kNotAvailable;
  for (size_t i = values.size(); i-- > 0;) {
    if (!better[i]) break;
    boundary = values[i];
  }
  return boundary;
}

// Runs the grid eps x swept value for the two variants and fills rows and boundaries.
// `configure` sets the swept generator parameter of a point.
void RunComparison(const ExperimentOptions& options, const std::vector<double>& swept,
                   const std::function<void(double, ThesisSampleOptions*)>& configure,
                   const std::vector<CalibrationOptions>& variants, const char* simple_name,
                   const char* alternative_name, bool sweep_is_alpha,
                   const std::function<double(const ErrorStats&)>& metric, uint64_t stream,
                   ExperimentResult* result) {
  std::vector<ThesisSampleOptions> points;
  for (double eps : options.model_eps_deg) {
    for (double value : swept) {
      ThesisSampleOptions point;
      point.num_poses = options.num_poses;
      point.eps_deg = eps;
      configure(value, &point);
      points.push_back(point);
    }
  }
  const auto stats = RunGrid(points, variants, options, stream);

  const char* names[] = {simple_name, alternative_name};
  for (int v = 0; v < 2; ++v) {
    for (size_t e = 0; e < options.model_eps_deg.size(); ++e) {
      for (size_t s = 0; s < swept.size(); ++s) {
        const size_t p = e * swept.size() + s;
        ExperimentRow row;
        row.series = names[v];
        row.eps_deg = options.model_eps_deg[e];
        row.num_poses = options.num_poses;
        (sweep_is_alpha ? row.alpha_max_deg : row.max_scale_error_pct) = swept[s];
        row.errors = stats[p][v];
        result->rows.push_back(row);
      }
    }
  }
  for (size_t e = 0; e < options.model_eps_deg.size(); ++e) {
    std::vector<bool> better;
    for (size_t s = 0; s < swept.size(); ++s) {
      const size_t p = e * swept.size() + s;
      better.push_back(AlternativeBetter(stats[p][0], stats[p][1], options.samples, metric));
    }
    result->boundary.push_back({options.model_eps_deg[e], Boundary(swept, better)});
  }
}

std::string SamplesNote(const ExperimentOptions& options) {
  return "generator: ThesisSample (thesis 5.1.2), one slave, K = " +
         std::to_string(options.num_poses) + " poses, " + std::to_string(options.samples) +
         " samples per point, seed " + std::to_string(options.seed) +
         "; both models are calibrated on the same samples";
}

}  // namespace

ExperimentResult RunMotionModel(const ExperimentOptions& options) {
  ExperimentResult result = NewExperimentResult(ExperimentKind::kMotionModel, options);
  if (!result.error.empty()) return result;
  const std::vector<CalibrationOptions> variants = {
      ThesisCalibrationOptions(Method::kLinear, MotionModel::kTranslational, ScaleModel::kFixed),
      ThesisCalibrationOptions(Method::kLinear, MotionModel::kGeneral, ScaleModel::kFixed)};
  RunComparison(
      options, options.alpha_max_deg,
      [](double alpha, ThesisSampleOptions* point) {
        // Pose k rotates by (k / K) alpha about a random axis; alpha = 0: no rotation at all.
        point->fixed_rotation_deg = alpha;
        point->max_rotation_deg = alpha;
      },
      variants, "translational", "general", /*sweep_is_alpha=*/true,
      [](const ErrorStats& s) { return s.rot_mean_deg; }, kMotionModelStream, &result);
  result.notes.push_back(
      "calibrator: Method::kLinear (LLS, as in the thesis), series general = "
      "MotionModel::kGeneral, translational = MotionModel::kTranslational; scale_model fixed, "
      "pairs since start, alpha_threshold_deg = 0, misfit removal off (outlier_mad_factor 1e9)");
  result.notes.push_back(SamplesNote(options) +
                         "; pose k rotates by (k/K) alpha_max about a random axis");
  result.notes.push_back(
      "errors: rot_mean_deg = mean rotation orientation error over solved estimates; the "
      "translational model does not estimate positions (dir/dist empty)");
  result.notes.push_back(
      "equal-error boundary: for each eps the smallest alpha_max from which on (to the end of "
      "the grid) the general model has the lower mean rotation error and at most 1 % more "
      "failures; empty = not reached within the grid");
  return result;
}

ExperimentResult RunScaleModel(const ExperimentOptions& options) {
  ExperimentResult result = NewExperimentResult(ExperimentKind::kScaleModel, options);
  if (!result.error.empty()) return result;
  const int partitions = options.partitions;  // 0: one per pose, resolved per sample
  const std::vector<CalibrationOptions> variants = {
      ThesisCalibrationOptions(Method::kLinear, MotionModel::kGeneral, ScaleModel::kFixed),
      ThesisCalibrationOptions(Method::kLinear, MotionModel::kGeneral, ScaleModel::kPartitions,
                               partitions)};
  RunComparison(
      options, options.max_scale_error_pct,
      [](double pct, ThesisSampleOptions* point) { point->max_scale_error = pct / 100.0; },
      variants, "fixed", "time-dependent", /*sweep_is_alpha=*/false,
      [](const ErrorStats& s) { return s.dir_mean_deg; }, kScaleModelStream, &result);
  result.notes.push_back(
      "calibrator: Method::kLinear (LLS, as in the thesis), series fixed = ScaleModel::kFixed, "
      "time-dependent = ScaleModel::kPartitions with " +
      (partitions > 0 ? std::to_string(partitions) + " partitions"
                      : std::string("one partition per pose (n = K, the thesis worst case; the "
                                    "generator's scale error differs at every pose)")) +
      "; motion_model general, pairs since start, alpha_threshold_deg = 0, misfit removal off");
  result.notes.push_back(SamplesNote(options) +
                         "; slave position k scaled by 1 + (k/K) max_scale_error");
  result.notes.push_back(
      "errors: dir_mean_deg = mean position orientation error over solved estimates; the "
      "time-dependent model has no single scale (scale columns empty)");
  result.notes.push_back(
      "equal-error boundary: for each eps the smallest max_scale_error from which on (to the "
      "end of the grid) the time-dependent model has the lower mean position orientation error "
      "and at most 1 % more failures; empty = not reached within the grid");
  return result;
}

ExperimentResult RunExperiment(ExperimentKind kind, const ExperimentOptions& options) {
  switch (kind) {
    case ExperimentKind::kStability:
      return RunStability(options);
    case ExperimentKind::kPoses:
      return RunPoses(options);
    case ExperimentKind::kMotionModel:
      return RunMotionModel(options);
    case ExperimentKind::kScaleModel:
      return RunScaleModel(options);
  }
  ExperimentResult result;
  result.error = "unknown experiment";
  return result;
}

}  // namespace rigcal::research
