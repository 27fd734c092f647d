#include "rigcal/calib/rig_calibrator.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>

#include "linear_solvers.h"
#include "model_selection.h"
#include "motion_data.h"
#include "motion_geometry.h"
#include "motion_statistics.h"
#include "refinement.h"
#include "rigcal/calib/logging.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/quaternion.h"
#include "scale_measurement.h"
#include "time_blocks.h"

namespace rigcal {
namespace {

using internal::MotionData;

std::string Fmt(double v, int precision = 2) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(precision);
  s << v;
  return s.str();
}

// Keeps the motions for which keep(m) is true; returns how many were removed.
template <typename Pred>
int KeepIf(std::vector<MotionData>* motions, Pred keep) {
  const size_t before = motions->size();
  motions->erase(std::remove_if(motions->begin(), motions->end(),
                                [&](const MotionData& m) { return !keep(m); }),
                 motions->end());
  return static_cast<int>(before - motions->size());
}

// Removes motions whose value exceeds median + factor * sigma (one-sided, for residual norms),
// or whose |value - median| does (two-sided). Never removes below `floor`.
int RemoveOutliers(std::vector<MotionData>* motions, const std::vector<double>& values,
                   double factor, double floor, bool two_sided) {
  const internal::RobustStats stats = internal::Robust(values);
  const double threshold = std::max(factor * stats.sigma, floor);
  std::vector<MotionData> kept;
  kept.reserve(motions->size());
  for (size_t k = 0; k < motions->size(); ++k) {
    const double d = two_sided ? std::abs(values[k] - stats.median) : values[k] - stats.median;
    if (d <= threshold) kept.push_back((*motions)[k]);
  }
  const int removed = static_cast<int>(motions->size() - kept.size());
  *motions = std::move(kept);
  return removed;
}

// Scale keys per motion: segment ids, or partition numbers of the time-ordered motions.
void AssignScaleKeys(ScaleModel model, int partitions, std::vector<MotionData>* motions) {
  if (model == ScaleModel::kSegments) {
    for (auto& m : *motions) m.scale_key = m.segment;
    return;
  }
  if (model != ScaleModel::kPartitions || partitions <= 1) {
    for (auto& m : *motions) m.scale_key = 0;
    return;
  }
  std::vector<size_t> order(motions->size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return (*motions)[a].t_ns < (*motions)[b].t_ns; });
  // |K^(ν)| = ceil(K / n), as the thesis's SetScalesPerCamera(n).
  const size_t per = (motions->size() + partitions - 1) / partitions;
  for (size_t rank = 0; rank < order.size(); ++rank) {
    (*motions)[order[rank]].scale_key = static_cast<int>(rank / std::max<size_t>(per, 1));
  }
}

// Maps the scale keys present to consecutive indices; returns the keys in index order.
std::vector<int> CompactScaleIndices(std::vector<MotionData>* motions) {
  std::map<int, int> index;
  for (const auto& m : *motions) index.emplace(m.scale_key, 0);
  std::vector<int> keys;
  for (auto& [key, idx] : index) {
    idx = static_cast<int>(keys.size());
    keys.push_back(key);
  }
  for (auto& m : *motions) m.scale_index = index[m.scale_key];
  return keys;
}

int CountSegments(const std::vector<MotionData>& motions) {
  std::map<int, int> seen;
  for (const auto& m : motions) seen[m.segment]++;
  return static_cast<int>(seen.size());
}

// Scales of `n` scale variables (scale_index of the motions) from the position equations.
using ScaleSolver = std::function<std::vector<double>(std::vector<MotionData>*, int n)>;

// Thesis 5.5: measured scales (4.18 / 4.31) that drift by more than the threshold (and by
// more than their own noise) call for time-dependent scales. Returns the partition count
// (1 = time-fixed).
// Planar motion translates perpendicular to the rotation axis, so the measurements of (4.18)
// are ratios of noise: the drift is tested with the position equations alone.
int ChoosePartitions(const std::vector<MotionData>& motions, double epsilon, bool translational,
                     bool planar, const CalibrationOptions& options,
                     const ScaleSolver& solve_scales, std::string* why) {
  std::vector<MotionData> sorted = motions;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const MotionData& a, const MotionData& b) { return a.t_ns < b.t_ns; });
  if (planar) {
    const int parts =
        std::min(10, static_cast<int>(sorted.size()) / options.min_motions_per_partition);
    if (parts < 2) {
      *why =
          "time-fixed scale (" + std::to_string(sorted.size()) + " motions, too few to test drift)";
      return 1;
    }
    AssignScaleKeys(ScaleModel::kPartitions, parts, &sorted);
    const int n = static_cast<int>(CompactScaleIndices(&sorted).size());
    const std::vector<double> scales = solve_scales(&sorted, n);
    double worst = 0.0;
    if (!scales.empty()) {
      const double center = internal::Robust(scales).median;
      for (double v : scales) worst = std::max(worst, std::abs(v - center) / std::abs(center));
    }
    if (worst > options.scale_deviation_threshold) {
      *why =
          "time-dependent scale: the position equations give partition scales deviating by "
          "up to " +
          Fmt(100 * worst, 1) + " % (threshold " + Fmt(100 * options.scale_deviation_threshold, 1) +
          " %)";
      return parts;
    }
    *why = "time-fixed scale: the position equations give partition scales within " +
           Fmt(100 * worst, 2) + " %";
    return 1;
  }
  const auto measurements = internal::MeasureScales(sorted, epsilon, translational);
  const int count = static_cast<int>(measurements.size());
  const int parts = std::min(10, count / options.min_motions_per_partition);
  if (parts < 2) {
    *why = "time-fixed scale (" + std::to_string(count) +
           " scale measurements, too few to test drift)";
    return 1;
  }
  std::vector<double> all;
  for (const auto& m : measurements) all.push_back(m.value);
  const double overall = internal::Robust(all).median;
  double worst = 0.0;
  bool significant = false;
  for (int p = 0; p < parts; ++p) {
    const int lo = p * count / parts, hi = (p + 1) * count / parts;
    std::vector<double> v;
    for (int k = lo; k < hi; ++k) v.push_back(measurements[k].value);
    const auto stats = internal::Robust(v);
    const double dev = std::abs(stats.median - overall) / std::abs(overall);
    const double standard_error = 1.2533 * stats.sigma / std::sqrt(static_cast<double>(v.size()));
    worst = std::max(worst, dev);
    if (dev > options.scale_deviation_threshold &&
        std::abs(stats.median - overall) > 3.0 * standard_error) {
      significant = true;
    }
  }
  if (significant) {
    // The ratios of (4.18) are noisy and can be biased by geometry; confirm the drift with the
    // position equations (4.17), whose per-partition scales are far better determined.
    std::vector<MotionData> work = sorted;
    AssignScaleKeys(ScaleModel::kPartitions, parts, &work);
    const int n = static_cast<int>(CompactScaleIndices(&work).size());
    const std::vector<double> scales = solve_scales(&work, n);
    double lls_worst = 0.0;
    if (!scales.empty()) {
      std::vector<double> sorted_scales = scales;
      const double center = internal::Robust(sorted_scales).median;
      for (double v : scales)
        lls_worst = std::max(lls_worst, std::abs(v - center) / std::abs(center));
    }
    if (lls_worst > options.scale_deviation_threshold) {
      *why = "time-dependent scale: scales deviate by up to " + Fmt(100 * lls_worst, 1) +
             " % over time (threshold " + Fmt(100 * options.scale_deviation_threshold, 1) + " %)";
      return parts;
    }
    *why = "time-fixed scale: measured scales (4.18) vary by up to " + Fmt(100 * worst, 1) +
           " %, but the position equations give partition scales within " +
           Fmt(100 * lls_worst, 1) + " %";
    return 1;
  }
  *why = "time-fixed scale: measured scales deviate by at most " + Fmt(100 * worst, 1) + " %";
  return 1;
}

// Sums of the linear equations of the motions, one scale variable per scale_index.
internal::MotionStatistics StatisticsOf(const std::vector<MotionData>& motions) {
  internal::MotionStatistics stats;
  for (const auto& m : motions) stats.Add(m, m.scale_index, 1.0);
  return stats;
}

// The linear solution of a rotating rig (general or planar, model_selection.h) with the
// quaternion signs of the motions aligned to it. `scales` is indexed by scale_index.
struct RotatingFit {
  internal::RotatingSolution solution;
  std::vector<double> scales;
};

RotatingFit SolveRotatingLinear(std::vector<MotionData>* motions, int num_scales,
                                MotionModel requested,
                                const internal::ModelSelectionOptions& select,
                                const internal::AxisPrior& prior) {
  internal::SolveLinearRotation(motions);  // signs, incl. motions near 180 degrees
  RotatingFit fit;
  fit.solution = internal::SolveRotating(StatisticsOf(*motions), requested, select, prior);
  if (fit.solution.ok && fit.solution.rotation_from_planar) {
    std::vector<MotionData> aligned = *motions;
    internal::AlignSignsWith(ToWxyz(fit.solution.q), &aligned);
    bool changed = false;
    for (size_t k = 0; k < aligned.size(); ++k)
      changed = changed || aligned[k].qi != (*motions)[k].qi;
    if (changed) {
      *motions = std::move(aligned);
      fit.solution = internal::SolveRotating(StatisticsOf(*motions), requested, select, prior);
    }
  }
  fit.scales.assign(num_scales, 0.0);
  for (const auto& [index, scale] : fit.solution.scales) {
    if (index >= 0 && index < num_scales) fit.scales[index] = scale;
  }
  return fit;
}

std::string Vec3Text(const Eigen::Vector3d& v) {
  std::string text = "[";  // appended, not "[" + ...: GCC 12 warns (-Wrestrict) on that
  text += Fmt(v.x(), 3) + ", " + Fmt(v.y(), 3) + ", " + Fmt(v.z(), 3) + "]";
  return text;
}

SlaveCalibration Fail(SlaveCalibration r, Termination t, const std::string& message) {
  r.termination = t;
  r.message = message;
  return r;
}

}  // namespace

SlaveCalibration CalibrateSlave(const std::vector<RigMotion>& motions,
                                const CalibrationOptions& options, const std::string& name) {
  auto log = ModuleLogger("calib");
  SlaveCalibration r;
  r.name = name;
  if (const Status checked = options.Check(); !checked.ok()) {
    return Fail(r, Termination::kInvalidInput, "invalid options: " + checked.message());
  }

  std::vector<MotionData> data = internal::ToMotionData(motions);
  r.motions.total = static_cast<int>(data.size());
  const int non_finite = KeepIf(&data, [](const MotionData& m) {
    return m.q0.allFinite() && m.qi.allFinite() && m.C0.allFinite() && m.Ci.allFinite();
  });
  r.motions.residual_outlier += non_finite;

  double max_rotation = 0.0;
  for (const auto& m : data) max_rotation = std::max(max_rotation, m.angle0);
  r.observability.max_rotation_deg = max_rotation * kDegPerRad;

  // Thesis 5.2: the purely translational model below the equal-error boundary, which scales
  // with the measured rotation noise (model_selection.h).
  r.observability.rotation_noise_deg = internal::RotationNoiseDeg(data);
  r.observability.translational_below_deg = internal::TranslationalBelowDeg(
      options.alpha_maxrot_deg, options.alpha_maxrot_noise_deg, r.observability.rotation_noise_deg,
      options.alpha_threshold_deg);
  MotionModel requested = options.motion_model;
  if (requested == MotionModel::kAuto &&
      max_rotation * kDegPerRad < r.observability.translational_below_deg) {
    requested = MotionModel::kTranslational;
  }
  const bool translational = requested == MotionModel::kTranslational;
  r.motion_model = translational ? MotionModel::kTranslational : MotionModel::kGeneral;

  if (!translational) {
    const double alpha = options.alpha_threshold_deg * kRadPerDeg;
    r.motions.small_rotation = KeepIf(
        &data, [alpha](const MotionData& m) { return m.angle0 >= alpha && m.anglei >= alpha; });
  } else {
    r.motions.small_rotation =
        KeepIf(&data, [](const MotionData& m) { return m.C0.norm() > 0.0 && m.Ci.norm() > 0.0; });
  }
  // Scale-free invariant: master and slave motions rotate by the same angle.
  {
    std::vector<double> diff;
    for (const auto& m : data) diff.push_back((m.angle0 - m.anglei) * kDegPerRad);
    r.motions.angle_mismatch = RemoveOutliers(&data, diff, options.outlier_mad_factor,
                                              options.angle_invariant_floor_deg, true);
  }

  const int min_motions = options.min_motions;
  if (static_cast<int>(data.size()) < min_motions) {
    std::ostringstream msg;
    if (translational) {
      msg << "need >= " << min_motions << " motions with translation, got " << data.size();
    } else {
      msg << "need >= " << min_motions
          << " motions with rotation >= " << Fmt(options.alpha_threshold_deg, 1) << " deg, got "
          << data.size() << " (largest rotation " << Fmt(r.observability.max_rotation_deg, 2)
          << " deg)";
    }
    r.motions.used = static_cast<int>(data.size());
    return Fail(r, Termination::kInsufficientMotion, msg.str());
  }

  // What the motion cannot determine is taken from the nominal mounting, when there is one:
  // the prior on C along the mean rotation axis (its axis is known once the motions are).
  const auto nominal_it = options.nominal.find(name);
  const Similarity* nominal = nominal_it == options.nominal.end() ? nullptr : &nominal_it->second;
  internal::ModelSelectionOptions select;
  select.planar_axis_spread_deg = options.planar_axis_spread_deg;
  select.min_tilt_snr = options.min_tilt_snr;
  select.max_axis_std_ratio = options.max_axis_std_ratio;
  select.general_axis_spread_deg = options.general_axis_spread_deg;
  internal::AxisPrior prior;
  if (nominal != nullptr) {
    prior.given = true;
    prior.nominal_C = nominal->C;
    prior.sigma = options.nominal_sigma;
  }
  const ScaleSolver solve_scales = [&](std::vector<MotionData>* work, int n) {
    if (translational) return internal::SolveTranslationalScales(*work, n);
    const RotatingFit fit = SolveRotatingLinear(work, n, requested, select, prior);
    return fit.solution.ok ? fit.scales : std::vector<double>{};
  };

  // Scale model.
  double rms_ci = 0.0;
  for (const auto& m : data) rms_ci += m.Ci.squaredNorm();
  rms_ci = std::sqrt(rms_ci / data.size());
  const double epsilon =
      options.scale_dot_epsilon > 0.0 ? options.scale_dot_epsilon : 1e-3 * rms_ci;
  ScaleModel scale_model = options.scale_model;
  int partitions = options.partitions;
  std::string scale_why;
  if (scale_model == ScaleModel::kAuto) {
    if (CountSegments(data) > 1) {
      scale_model = ScaleModel::kSegments;
      scale_why = "one scale per odometry segment (" + std::to_string(CountSegments(data)) + ")";
    } else {
      bool planar_motion = false;
      if (!translational) {
        std::vector<MotionData> work = data;  // one scale (scale_index 0)
        planar_motion = SolveRotatingLinear(&work, 1, requested, select, prior).solution.model ==
                        MotionModel::kPlanar;
      }
      partitions = ChoosePartitions(data, epsilon, translational, planar_motion, options,
                                    solve_scales, &scale_why);
      scale_model = partitions > 1 ? ScaleModel::kPartitions : ScaleModel::kFixed;
    }
  }
  r.scale_model = scale_model;
  AssignScaleKeys(scale_model, partitions, &data);

  // Linear estimate with misfit removal (rounds of solve, residuals, outlier test).
  Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
  internal::LinearPositionScale pos;
  std::vector<int> scale_keys;
  RotatingFit fit;
  for (int round = 0;; ++round) {
    scale_keys = CompactScaleIndices(&data);
    const int num_scales = static_cast<int>(scale_keys.size());
    if (!translational) {
      fit = SolveRotatingLinear(&data, num_scales, requested, select, prior);
      dq = fit.solution.q;
      pos.C = fit.solution.C;
      pos.scales = fit.scales;
      pos.ok = fit.solution.ok;
      pos.min_eigenvalue = fit.solution.observability.position_min_eigenvalue;
    } else {
      dq = internal::SolveTranslationalRotation(data);
      pos.C.setZero();
      pos.scales = internal::SolveTranslationalScales(data, num_scales);
      pos.ok = true;
    }
    if (!pos.ok || round >= options.max_outlier_rounds) break;
    std::vector<double> res_pos, res_rot;
    double typical = 0.0;
    for (const auto& m : data) {
      const double s = pos.scales[m.scale_index];
      res_pos.push_back(translational ? internal::TranslationalResidual(m, dq, s)
                                      : internal::PositionResidual(m, dq, pos.C, s));
      if (!translational) res_rot.push_back(internal::RotationResidual(m, ToWxyz(dq)));
      typical = std::max(typical, m.C0.norm());
    }
    int removed =
        RemoveOutliers(&data, res_pos, options.outlier_mad_factor, 1e-9 * (1 + typical), false);
    if (!translational && removed == 0) {
      removed = RemoveOutliers(&data, res_rot, options.outlier_mad_factor, 1e-9, false);
    }
    r.motions.residual_outlier += removed;
    if (removed == 0) break;
    if (static_cast<int>(data.size()) < min_motions) break;
  }
  r.motions.used = static_cast<int>(data.size());
  if (!translational) {
    Observability figures = fit.solution.observability;
    figures.max_rotation_deg = r.observability.max_rotation_deg;
    figures.rotation_noise_deg = r.observability.rotation_noise_deg;
    figures.translational_below_deg = r.observability.translational_below_deg;
    r.observability = figures;
    r.motion_model = fit.solution.model;
  }
  const bool planar = r.motion_model == MotionModel::kPlanar;
  if (static_cast<int>(data.size()) < min_motions) {
    return Fail(r, Termination::kInsufficientMotion,
                "need >= " + std::to_string(min_motions) + " consistent motions, got " +
                    std::to_string(data.size()) + " after misfit removal");
  }
  // The thesis's general model on planar motion (the axes tilt no more than noise explains):
  // the rotation about the axis and C along it are not determined, whether or not the
  // equations happen to be singular. (A merely large σ along the axis is reported, not failed.)
  const Observability& figures = r.observability;
  if (options.motion_model == MotionModel::kGeneral && !translational &&
      ((figures.tilt_snr < options.min_tilt_snr &&
        figures.axis_spread_deg < options.general_axis_spread_deg) ||
       figures.axis_spread_deg < options.planar_axis_spread_deg)) {
    r.observability.planar = true;
    r.unobservable = {figures.planar_axis};
    r.estimate.q = dq;
    if (pos.ok) r.estimate.C = pos.C;
    return Fail(r, Termination::kDegenerate,
                "planar motion (the rotation axes tilt no more than rotation noise explains: "
                "spread " +
                    Fmt(figures.axis_spread_deg, 3) + " deg, tilt SNR " + Fmt(figures.tilt_snr, 1) +
                    "): the rotation about the axis and C along it are not determined by the "
                    "general model; use the planar model (motion model auto or planar)");
  }
  if (!pos.ok) {
    if (planar) {
      return Fail(r, Termination::kDegenerate,
                  "planar motion (" + fit.solution.why +
                      "), but the in-plane translation equations are singular: the motions do "
                      "not determine the angle about the axis, position and scale");
    }
    return Fail(r, Termination::kDegenerate,
                "the position/scale equations (4.16) are singular: the motions do not determine "
                "position and scale");
  }

  // Noise levels from the linear residuals whiten the non-linear problem.
  const int num_scales = static_cast<int>(scale_keys.size());
  const int k = static_cast<int>(data.size());
  double ss_rot = 0.0, ss_pos = 0.0, typical = 0.0;
  for (const auto& m : data) {
    const double s = pos.scales[m.scale_index];
    if (!translational) ss_rot += std::pow(internal::RotationResidual(m, ToWxyz(dq)), 2);
    ss_pos += std::pow(translational ? internal::TranslationalResidual(m, dq, s)
                                     : internal::PositionResidual(m, dq, pos.C, s),
                       2);
    typical = std::max(typical, m.C0.norm());
  }
  internal::RefinementInput input;
  input.q = dq;
  input.C = pos.C;
  input.scales = pos.scales;
  input.translational = translational;
  input.sigma_rotation = std::max(std::sqrt(ss_rot / std::max(1, 4 * k - 3)), 1e-12);
  const int pos_unknowns = translational ? 0 : (planar ? 2 : 3);
  const int pos_dof = std::max(1, 3 * k - pos_unknowns - num_scales - 3);
  input.sigma_position = std::max(std::sqrt(ss_pos / pos_dof), 1e-12 * (1.0 + typical));
  // The reduced parameter set: C = B p + h a about the mean rotation axis a; h fixed (planar,
  // at the prior or 0) or pulled towards the prior by a weighted term.
  const Eigen::Vector3d axis = r.observability.planar_axis;
  const double axis_prior = prior.given ? axis.dot(prior.nominal_C) : 0.0;
  // (The general model without a weighted prior keeps C a plain 3-vector.)
  const bool weighted_prior = prior.given && prior.sigma > 0.0;
  if (!translational && axis.norm() > 0.5 && (planar || weighted_prior)) {
    input.axis = axis;
    input.axis_prior = axis_prior;
    input.axis_prior_sigma = prior.given ? prior.sigma : 0.0;
    // Planar: nothing but the prior determines h, so it is held at the prior's value (or 0).
    input.axis_offset_fixed = planar;
  }

  const auto measurements = internal::MeasureScales(data, epsilon, translational);
  std::vector<internal::ScaleSummary> summaries;
  for (int s = 0; s < num_scales; ++s) {
    summaries.push_back(internal::SummarizeScales(measurements, data, s));
    // Prior of (4.27), σ² = sum (λ - λ^k)² as in the thesis; none for planar motion, whose
    // measurements (4.18) are ratios of noise (translation perpendicular to the axis).
    input.priors.push_back(
        {summaries[s].mean, summaries[s].count >= 2 && !planar ? summaries[s].sigma_thesis : 0.0});
  }

  const int blocks = options.covariance_time_blocks;
  if (blocks > 0 && k >= 4 * blocks) input.blocks = internal::TimeBlocks(data, blocks);
  const bool solve = options.method == Method::kNonlinear;
  const internal::RefinementResult refined = internal::RefineNonlinear(data, input, options, solve);

  r.estimate.q = refined.q;
  r.estimate.C = translational ? Eigen::Vector3d::Zero() : refined.C;
  r.estimate.scale = refined.scales.empty() ? 1.0 : refined.scales[0];
  for (int s = 0; s < num_scales; ++s) {
    SegmentScale seg;
    seg.segment = scale_keys[s];
    seg.scale = refined.scales[s];
    seg.std = refined.scale_std[s];
    seg.measured_mean = summaries[s].mean;
    seg.measured_std = summaries[s].std;
    seg.measured_count = summaries[s].count;
    r.scales.push_back(seg);
  }
  if (refined.covariance_ok) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(refined.cov_rotation);
    r.rot_std_deg = std::sqrt(std::max(0.0, eig.eigenvalues()(2))) * kDegPerRad;
    r.pos_std = refined.cov_position.diagonal().cwiseMax(0.0).cwiseSqrt();
  }
  // Translations all along one line leave the rotation about it to their noise (Ceres's
  // covariance would take that noise for information).
  const bool parallel =
      translational && !std::isfinite(internal::TranslationalRotationStd(data, r.estimate.q));
  if (parallel) r.rot_std_deg = std::numeric_limits<double>::infinity();
  if (translational) {
    r.position_observable = false;
    r.unobservable = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  } else if (planar) {
    r.unobservable = {axis};
    r.unobservable_from_prior = prior.given;
    r.axis_offset_std = std::numeric_limits<double>::quiet_NaN();
    if (prior.given && prior.sigma > 0.0) {
      r.axis_offset_std = prior.sigma;
      if (refined.covariance_ok) {
        const Eigen::Matrix3d cov =
            refined.cov_position + prior.sigma * prior.sigma * axis * axis.transpose();
        r.pos_std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
      }
    }
  } else if (refined.covariance_ok) {
    r.axis_offset_std = weighted_prior
                            ? refined.axis_std
                            : std::sqrt(std::max(0.0, axis.dot(refined.cov_position * axis)));
  } else {
    r.axis_offset_std = fit.solution.axis_std;
  }

  std::ostringstream msg;
  msg << r.motions.used << " motions used, " << r.motions.rejected() << " rejected ("
      << r.motions.small_rotation << (translational ? " without translation" : " small rotation")
      << ", " << r.motions.angle_mismatch << " angle mismatch, " << r.motions.residual_outlier
      << " outliers); " << ToString(r.motion_model) << " motion";
  // Why the motion model: the largest rotation against the equal-error boundary at the
  // measured rotation noise (thesis 5.2), then the figures of general vs planar.
  const std::string boundary_text =
      options.alpha_maxrot_noise_deg > 0.0
          ? Fmt(r.observability.translational_below_deg, 2) +
                " deg, the equal-error boundary at the measured rotation noise " +
                Fmt(r.observability.rotation_noise_deg, 3) + " deg"
          : Fmt(r.observability.translational_below_deg, 1) + " deg";
  std::vector<std::string> why;
  if (options.motion_model == MotionModel::kAuto) {
    why.push_back("largest rotation " + Fmt(r.observability.max_rotation_deg, 2) +
                  (translational ? " deg < " : " deg >= ") + boundary_text);
  } else if (translational) {
    why.push_back("largest rotation " + Fmt(r.observability.max_rotation_deg, 2) + " deg");
  }
  if (!translational && !fit.solution.why.empty()) why.push_back(fit.solution.why);
  if (!why.empty()) {
    msg << " (" << why[0];
    for (size_t j = 1; j < why.size(); ++j) msg << "; " << why[j];
    msg << ")";
  }
  if (parallel) {
    msg << ": the translations are all parallel, so the rotation about their direction is "
           "undetermined (drive a curve)";
  } else if (translational) {
    msg << ": rotation and scale only, position unobservable";
  } else if (planar) {
    msg << ": C along the rotation axis " << Vec3Text(axis) << " is unobservable";
    if (prior.given) {
      msg << ", taken from the nominal mounting (" << Fmt(axis_prior, 4) << " along the axis";
      if (prior.sigma > 0.0) msg << ", sigma " << Fmt(prior.sigma, 4);
      msg << ")";
    } else {
      msg << ", reported as 0 (unknown; a nominal mounting would fill it in)";
    }
  } else if (r.observability.axis_std_ratio > 3.0 && std::isfinite(r.axis_offset_std)) {
    msg << "; nearly planar: C along the mean rotation axis " << Vec3Text(axis) << " has sigma "
        << Fmt(r.axis_offset_std, 4);
    if (prior.given && prior.sigma > 0.0) msg << " (with the nominal mounting as a prior)";
  }
  msg << "; " << (scale_why.empty() ? ToString(scale_model) + " scale model" : scale_why);
  if (refined.clustered_larger) {
    msg << "; sigma with errors shared within " << blocks
        << " time blocks (motions close in time share their errors)";
  }
  if (solve) msg << "; refinement: " << refined.message;
  r.termination = parallel                        ? Termination::kDegenerate
                  : (solve && !refined.converged) ? Termination::kNoConvergence
                                                  : Termination::kConverged;
  r.message = msg.str();
  log->debug("slave '{}': {}", name, r.message);
  return r;
}

RigCalibration CalibrateRig(const RigRecording& recording, const CalibrationOptions& options) {
  RigCalibration out;
  out.master = recording.master.name;
  const std::string invalid = recording.Validate();
  const bool options_ok = options.Check().ok();
  std::vector<IndexPair> pairs;
  if (invalid.empty() && options_ok) pairs = SelectPairs(recording, options.pairs);
  out.pairs_selected = static_cast<int>(pairs.size());
  for (size_t i = 0; i < recording.slaves.size(); ++i) {
    const auto& name = recording.slaves[i].name;
    if (!invalid.empty()) {
      SlaveCalibration r;
      r.name = name;
      out.slaves.push_back(Fail(r, Termination::kInvalidInput, "invalid recording: " + invalid));
      continue;
    }
    out.slaves.push_back(
        CalibrateSlave(MotionsForSlave(recording, static_cast<int>(i), pairs), options, name));
  }
  return out;
}

std::string ToString(Termination t) {
  switch (t) {
    case Termination::kConverged:
      return "converged";
    case Termination::kNoConvergence:
      return "no_convergence";
    case Termination::kInsufficientMotion:
      return "insufficient_motion";
    case Termination::kDegenerate:
      return "degenerate";
    case Termination::kInvalidInput:
      return "invalid_input";
  }
  return "?";
}

std::string RigCalibration::BriefReport() const {
  std::ostringstream s;
  s << "master " << master << ", " << pairs_selected << " time pairs\n";
  for (const auto& r : slaves) {
    s << "  " << r.name << ": " << ToString(r.termination) << " - " << r.message << "\n";
  }
  return s.str();
}

}  // namespace rigcal
