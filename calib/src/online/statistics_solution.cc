// SPDX-License-Identifier: Apache-2.0
// The recursive estimator's linear solution of a slave's statistics (statistics_solution.h).
#include "online/statistics_solution.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "models/model_selection.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {

double OnlineTranslationalBelowDeg(const RigEstimatorOptions& o,
                                   const RunningMeanSquare& angle_var) {
  const ModelSelectionOptions& m = o.model_selection;
  if (m.alpha_maxrot_noise_deg <= 0.0 || angle_var.count < o.gate_after_motions) {
    return std::max(m.alpha_maxrot_deg, o.pair_min_angle_deg);
  }
  return TranslationalBelowDeg(m.alpha_maxrot_deg, m.alpha_maxrot_noise_deg,
                               std::sqrt(std::max(angle_var.value, 0.0)), o.pair_min_angle_deg);
}

MotionModelChoice ChooseMotionModel(const RigEstimatorOptions& o, bool rotating,
                                    const RunningMeanSquare& angle_var) {
  MotionModelChoice choice;
  choice.rotating = rotating;
  choice.noise_deg = std::sqrt(angle_var.value);
  choice.boundary_deg = OnlineTranslationalBelowDeg(o, angle_var);
  return choice;
}

SlaveCalibration SolveStatistics(const MotionStatistics& stats, const RigEstimatorOptions& opt,
                                 const std::optional<Similarity>& nominal, int current_segment,
                                 const MotionModelChoice& choice, bool* general) {
  SlaveCalibration r;
  r.motions.used = stats.motions();
  r.observability.max_rotation_deg = stats.max_rotation() * kDegPerRad;
  if (stats.motions() < 2 || stats.weight() <= 0.0) {
    r.termination = Termination::kInsufficientMotion;
    r.message = "initialising: " + std::to_string(stats.motions()) + " motions so far";
    return r;
  }
  const bool translational = !choice.rotating;
  r.motion_model = translational ? MotionModel::kTranslational : MotionModel::kGeneral;
  std::map<int, double> scales;
  bool ok = true;
  if (translational) {
    r.estimate.q = stats.SolveTranslationalRotation();
    scales = stats.SolveTranslationalScales();
    // Infinite when the translations leave a rotation undetermined (driving straight).
    r.rot_std_deg = stats.TranslationalRotationStd(r.estimate.q) * kDegPerRad;
    r.position_observable = false;
    r.unobservable = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    if (nominal) r.estimate.C = nominal->C;
  } else {
    ModelSelectionOptions select = opt.model_selection;
    // Hysteresis: stay general unless clearly planar, once the figures rest on enough motions
    // (the first few motions' tilt SNR is a ratio of a handful of noise samples).
    if (general != nullptr && *general && stats.motions() >= opt.converged_min_motions) {
      select.min_tilt_snr /= opt.planar_hysteresis;
      select.max_axis_std_ratio *= opt.planar_hysteresis;
    }
    AxisPrior prior;
    if (nominal) {
      prior.given = true;
      prior.nominal_C = nominal->C;
      prior.sigma = opt.nominal_sigma;
    }
    const RotatingSolution sol = SolveRotating(stats, MotionModel::kAuto, select, prior);
    if (general != nullptr) *general = sol.model == MotionModel::kGeneral;
    r.motion_model = sol.model;
    r.observability = sol.observability;
    r.estimate.q = sol.q;
    r.estimate.C = sol.C;
    scales = sol.scales;
    r.rot_std_deg = sol.rot_std_deg;
    r.pos_std = sol.cov_C.diagonal().cwiseMax(0.0).cwiseSqrt();
    r.axis_offset_std = sol.axis_std;
    if (sol.model == MotionModel::kPlanar) {
      r.unobservable.push_back(r.observability.planar_axis);
      r.unobservable_from_prior = sol.axis_from_prior;
    }
    r.message = sol.why;
    ok = sol.ok;
    if (!ok && nominal) r.estimate.C = nominal->C;
  }
  r.observability.rotation_noise_deg = choice.noise_deg;
  r.observability.translational_below_deg = choice.boundary_deg;
  for (const auto& [id, v] : stats.closed_scales()) {
    SegmentScale s;
    s.segment = id;
    s.scale = v;
    r.scales.push_back(s);
  }
  for (const auto& [id, v] : scales) {
    SegmentScale s;
    s.segment = id;
    s.scale = v;
    r.scales.push_back(s);
  }
  std::sort(r.scales.begin(), r.scales.end(),
            [](const SegmentScale& a, const SegmentScale& b) { return a.segment < b.segment; });
  r.estimate.scale = 1.0;
  for (const auto& s : r.scales) {
    if (s.segment == current_segment) r.estimate.scale = s.scale;
  }
  r.scale_model = r.scales.size() > 1 ? ScaleModel::kSegments : ScaleModel::kFixed;
  const bool finite = r.estimate.q.coeffs().allFinite() && r.estimate.C.allFinite() &&
                      std::isfinite(r.estimate.scale);
  r.termination = ok && finite ? Termination::kSolved : Termination::kDegenerate;
  return r;
}

}  // namespace rigcal::internal
