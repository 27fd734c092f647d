// SPDX-License-Identifier: Apache-2.0
#pragma once
// The synthetic experiments of thesis chapter 5.1-5.3, reproducing figures 5.1-5.6:
//   stability     (fig. 5.1 LLS, 5.2 NL): K = 4 poses, orientation error level eps 0..3 deg.
//   poses         (fig. 5.3 LLS, 5.4 NL): eps = 1 deg, K = 4..24 poses.
//   motion-model  (fig. 5.5): general vs purely translational motion model (LLS), rotation error
//                 over the maximal rig rotation alpha_max 0..25 deg for eps 0..3 deg.
//   scale-model   (fig. 5.6): time-fixed vs time-dependent scale model (LLS), position orientation
//                 error over the maximal scale error 0..100 % for eps 0..3 deg.
// Every sample is one thesis 5.1.2 problem (ThesisSample, one slave, motions (0, k) since the
// start); every series of a figure is calibrated on the same samples (paired comparison).
// Running an experiment returns rows; CSV, SVG and the text summary are made separately.

#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/base/status.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/plot/svg_plot.h"

namespace rigcal::research {

enum class ExperimentKind { kStability, kPoses, kMotionModel, kScaleModel };

// "stability", "poses", "motion-model", "scale-model".
std::string ToString(ExperimentKind kind);
// Inverse of ToString; false (and *kind unchanged) for any other name.
bool ParseExperimentKind(const std::string& name, ExperimentKind* kind);

// first, first + step, ..., last (last included when it lies on the grid up to rounding).
std::vector<double> LinearGrid(double first, double last, double step);

// Progress of a running experiment: `done` of `total` units of work (one unit = one sample of
// one grid point). Called at about every 10 % and at the end, from a worker thread, never
// concurrently with itself.
using ExperimentProgress = std::function<void(int64_t done, int64_t total)>;

struct ExperimentOptions {
  // Random problem instances per grid point (the thesis used 1e5).
  int samples = 200;
  // Results depend on seed and samples only, not on the number of threads.
  uint64_t seed = 1;
  // Worker threads; 0 = std::thread::hardware_concurrency().
  int threads = 2;
  // Sample geometries averaged for the Cramer-Rao bound of stability and poses; 0 = no bound.
  int crb_samples = 200;
  // Scale-model: scales of the time-dependent model; 0 = one per pose (n = K, the thesis worst
  // case, which matches the generator's scale error that differs at every pose).
  int partitions = 0;
  // K of stability, motion-model and scale-model (thesis: 4).
  int num_poses = 4;

  // Grids (thesis values by default).
  std::vector<double> stability_eps_deg = LinearGrid(0.0, 3.0, 0.1);
  double poses_eps_deg = 1.0;
  int poses_min = 4;
  int poses_max = 24;
  std::vector<double> model_eps_deg = {0.0, 1.0, 2.0, 3.0};
  std::vector<double> alpha_max_deg = LinearGrid(0.0, 25.0, 1.0);
  std::vector<double> max_scale_error_pct = LinearGrid(0.0, 100.0, 5.0);

  ExperimentProgress progress;  // optional

  // Success, or the first offending field and its constraint: "<field>: <constraint>".
  Status Check() const;
};

constexpr double kNotAvailable = std::numeric_limits<double>::quiet_NaN();

// Mean, RMS and median of the thesis 5.1.1 error measures over the estimates of one grid point
// (`usable`: the solve produced one, SlaveCalibration::solved(), whether or not the data support
// it: the thesis measures models forced against the data too). The mean is what the thesis plots;
// the RMS is what the Cramer-Rao bound bounds; the median is robust to the rare gross failures that
// dominate mean and RMS of small sample counts. A measure a model does not estimate (positions of
// the translational model, the single scale of the time-dependent model) is NaN.
struct ErrorStats {
  int usable = 0;
  int failed = 0;  // the calibrator reported no usable estimate
  double rot_mean_deg = kNotAvailable;
  double rot_rms_deg = kNotAvailable;
  double rot_median_deg = kNotAvailable;
  double dir_mean_deg = kNotAvailable;
  double dir_rms_deg = kNotAvailable;
  double dir_median_deg = kNotAvailable;
  double dist_mean_pct = kNotAvailable;
  double dist_rms_pct = kNotAvailable;
  double dist_median_pct = kNotAvailable;
  double scale_mean_pct = kNotAvailable;
  double scale_rms_pct = kNotAvailable;
  double scale_median_pct = kNotAvailable;
};

// Cramer-Rao bound (cramer_rao.h) averaged over sample geometries: the square root of the mean
// per-geometry variance bound, i.e. a bound on the RMS error over samples. Computed at 1 deg and
// scaled linearly to each eps (the linear-Gaussian bound is linear in eps).
struct BoundStats {
  int geometries = 0;  // geometries averaged
  int degenerate = 0;  // geometries whose parameters the poses do not determine (skipped)
  double rot_deg = kNotAvailable;
  double dir_deg = kNotAvailable;
  double dist_pct = kNotAvailable;
  double scale_pct = kNotAvailable;
  BoundStats Scaled(double factor) const;
};

struct ExperimentRow {
  // "lls", "nl" (stability, poses); "general", "translational" (motion-model);
  // "fixed", "time-dependent" (scale-model).
  std::string series;
  double eps_deg = 0.0;
  int num_poses = 0;
  double alpha_max_deg = kNotAvailable;        // motion-model only
  double max_scale_error_pct = kNotAvailable;  // scale-model only
  ErrorStats errors;
  BoundStats crb;  // stability and poses only
};

// Equal-error boundary of a model comparison at one eps: the smallest swept value (alpha_max in
// degrees, or the maximal scale error in percent) from which on, up to the end of the grid, the
// alternative model (general; time-dependent) has a lower mean error than the simple one
// (translational; fixed) by more than 1e-9 (a tie of exact solutions is no win), and fails in
// at most 1 % of the samples more. NaN when that does not happen within the grid.
struct EqualErrorBoundary {
  double eps_deg = 0.0;
  double value = kNotAvailable;
};

struct ExperimentResult {
  ExperimentKind kind = ExperimentKind::kStability;
  std::string error;  // non-empty when the options were invalid (then there are no rows)
  std::vector<ExperimentRow> rows;
  std::vector<EqualErrorBoundary> boundary;  // motion-model and scale-model
  std::vector<std::string> notes;            // options used and how to read the numbers
};

// The experiments. Thread-compatible; each uses options.threads worker threads internally and
// joins them before returning.
// An empty result of `kind`; its `error` is the options' Check() message (empty when valid).
ExperimentResult NewExperimentResult(ExperimentKind kind, const ExperimentOptions& options);

ExperimentResult RunStability(const ExperimentOptions& options);
ExperimentResult RunPoses(const ExperimentOptions& options);
ExperimentResult RunMotionModel(const ExperimentOptions& options);
ExperimentResult RunScaleModel(const ExperimentOptions& options);
ExperimentResult RunExperiment(ExperimentKind kind, const ExperimentOptions& options);

// ---- Output ----

// CSV with a header line and one line per row: experiment, series, eps_deg, num_poses,
// alpha_max_deg, max_scale_error_pct, usable, failed, the mean, RMS and median error columns
// (rot_mean_deg, rot_rms_deg, rot_median_deg, dir_*, dist_*, scale_*), and the
// bound columns crb_rot_deg, crb_dir_deg, crb_dist_pct, crb_scale_pct. Boundary entries follow
// as rows with series "equal_error_boundary" and the boundary in the swept column. Unavailable
// values are empty fields.
std::string ExperimentCsv(const ExperimentResult& result);

struct NamedFigure {
  std::string file_name;  // e.g. "fig5_1_lls.svg"
  plot::PlotFigure figure;
};

// The figures of an experiment: stability fig5_1_lls.svg and fig5_2_nl.svg, poses
// fig5_3_lls.svg and fig5_4_nl.svg (4 panels each: rotation, position direction, distance and
// scale error; measured mean and RMS, and the bound dashed), motion-model fig5_5.svg and
// scale-model fig5_6.svg (2 panels: the errors of both models per eps, and the equal-error
// boundary).
std::vector<NamedFigure> ExperimentFigures(const ExperimentResult& result);

// A fixed-width text table of the result followed by the boundary and the notes.
std::string FormatSummary(const ExperimentResult& result);

// Writes <name>.csv, <name>_summary.txt and the figures into `out_dir` (created if missing),
// each file atomically. Returns the written paths, or an error naming the file.
Expected<std::vector<std::string>> WriteExperimentOutputs(const ExperimentResult& result,
                                                          const std::string& out_dir);

// ---- Building blocks (also for benchmarks) ----

// Calibrator options of the thesis reproduction: the given method and models, pairs since the
// start (kSinceStart), alpha_threshold_deg = 0 and misfit removal effectively off (huge
// outlier_mad_factor), so that every motion is used; no covariance.
CalibrationOptions ThesisCalibrationOptions(Method method, MotionModel motion_model,
                                            ScaleModel scale_model, int partitions = 1);

// The random generator of sample `index` of stream `stream` (one stream per grid point or use).
std::mt19937_64 SampleRng(uint64_t seed, uint64_t stream, uint64_t index);

// Calibrates options.samples thesis samples of every grid point with every variant; returns the
// statistics [point][variant]. `stream` separates the random streams of different uses. Variants
// with ScaleModel::kPartitions and partitions <= 0 use one partition per pose of the point.
std::vector<std::vector<ErrorStats>> RunGrid(const std::vector<ThesisSampleOptions>& points,
                                             const std::vector<CalibrationOptions>& variants,
                                             const ExperimentOptions& options, uint64_t stream);

// Bound of K-pose thesis problems at eps = 1 deg, averaged over options.crb_samples geometries.
BoundStats AverageThesisBound(int num_poses, const ExperimentOptions& options);

}  // namespace rigcal::research
