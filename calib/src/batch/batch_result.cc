// SPDX-License-Identifier: Apache-2.0
// The result of the batch calibrator: estimate, σ, what is undetermined, message
// (batch_result.h).
#include "batch/batch_result.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "models/linear_solvers.h"
#include "models/model_explanation.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// The refined rotation, C, scales and their σ; the directions the model leaves undetermined.
// Returns whether the translations are all parallel (the rotation about them undetermined).
bool TakeRefinedEstimate(const BatchSetting& setting, const std::vector<MotionData>& data,
                         const LinearEstimate& linear, const BatchRefinement& refinement,
                         SlaveCalibration* out) {
  SlaveCalibration& r = *out;
  const RefinementResult& refined = refinement.refined;
  const bool translational = setting.translational;
  const bool planar = r.motion_model == MotionModel::kPlanar;
  const AxisPrior& prior = setting.prior;
  const Eigen::Vector3d axis = r.observability.planar_axis;
  r.estimate.q = refined.q;
  r.estimate.C = translational ? Eigen::Vector3d::Zero() : refined.C;
  r.estimate.scale = refined.scales.empty() ? 1.0 : refined.scales[0];
  for (size_t s = 0; s < linear.scale_keys.size(); ++s) {
    SegmentScale seg;
    seg.segment = linear.scale_keys[s];
    seg.scale = refined.scales[s];
    seg.std = refined.scale_std[s];
    seg.measured_mean = refinement.summaries[s].mean;
    seg.measured_std = refinement.summaries[s].std;
    seg.measured_count = refinement.summaries[s].count;
    r.scales.push_back(seg);
  }
  // Without a covariance (not computed, or Ceres failed) every σ is unknown (NaN), never 0.
  constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
  r.rot_std_deg = kUnknown;
  r.pos_std.setConstant(kUnknown);
  if (refined.covariance_ok) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(refined.cov_rotation);
    r.rot_std_deg = std::sqrt(std::max(0.0, eig.eigenvalues()(2))) * kDegPerRad;
    r.pos_std = refined.cov_position.diagonal().cwiseMax(0.0).cwiseSqrt();
  } else {
    for (SegmentScale& seg : r.scales) seg.std = kUnknown;
  }
  // Translations all along one line leave the rotation about it to their noise (Ceres's
  // covariance would take that noise for information).
  const bool parallel =
      translational && !std::isfinite(TranslationalRotationStd(data, r.estimate.q));
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
    const bool weighted_prior = prior.given && prior.sigma > 0.0;
    r.axis_offset_std = weighted_prior
                            ? refined.axis_std
                            : std::sqrt(std::max(0.0, axis.dot(refined.cov_position * axis)));
  } else {
    r.axis_offset_std = kUnknown;
  }
  return parallel;
}

// "<used> motions used, <rejected> rejected (...); <model explanation>; <scale model>[; time
// blocks][; refinement: ...]".
std::string BatchMessage(const CalibrationOptions& options, const BatchSetting& setting,
                         const LinearEstimate& linear, const BatchRefinement& refinement,
                         const ScaleModelChoice& scale, bool parallel, const SlaveCalibration& r) {
  const bool translational = setting.translational;
  std::ostringstream msg;
  msg << r.motions.used << " motions used, " << r.motions.rejected() << " rejected ("
      << r.motions.small_rotation << (translational ? " without translation" : " small rotation")
      << ", " << r.motions.angle_mismatch << " angle mismatch, " << r.motions.residual_outlier
      << " outliers); ";
  // Why the motion model: the largest rotation against the equal-error boundary at the
  // measured rotation noise (thesis 5.2), then the figures of general vs planar.
  ModelExplanation e;
  e.model = r.motion_model;
  e.figures = r.observability;
  e.boundary = options.motion_model == MotionModel::kAuto ? ModelExplanation::Boundary::kCompared
               : translational ? ModelExplanation::Boundary::kLargestRotation
                               : ModelExplanation::Boundary::kNone;
  e.boundary_from_noise = options.model_selection.alpha_maxrot_noise_deg > 0.0;
  e.selection = linear.fit.solution.why;
  e.parallel = parallel;
  e.axis_offset_std = r.axis_offset_std;
  e.nominal = setting.prior.given;
  e.nominal_along_axis = setting.AxisPriorAlong(r.observability.planar_axis);
  e.nominal_sigma = setting.prior.sigma;
  msg << ExplainModel(e);
  msg << "; " << (scale.why.empty() ? ToString(r.scale_model) + " scale model" : scale.why);
  if (refinement.refined.clustered_larger) {
    msg << "; sigma with errors shared within " << refinement.time_blocks
        << " time blocks (motions close in time share their errors)";
  }
  if (refinement.solved) msg << "; refinement: " << refinement.refined.message;
  return msg.str();
}

}  // namespace

SlaveCalibration Failed(SlaveCalibration r, Termination t, const std::string& message) {
  r.termination = t;
  r.message = message;
  return r;
}

void TakeLinearFigures(const BatchSetting& setting, const LinearEstimate& linear, int used,
                       SlaveCalibration* r) {
  r->motions.used = used;
  if (setting.translational) return;
  Observability figures = linear.fit.solution.observability;
  figures.max_rotation_deg = r->observability.max_rotation_deg;
  figures.rotation_noise_deg = r->observability.rotation_noise_deg;
  figures.translational_below_deg = r->observability.translational_below_deg;
  r->observability = figures;
  r->motion_model = linear.fit.solution.model;
}

std::optional<SlaveCalibration> UndeterminedResult(const CalibrationOptions& options,
                                                   const BatchSetting& setting,
                                                   const LinearEstimate& linear,
                                                   const SlaveCalibration& r) {
  const int used = r.motions.used;
  if (used < options.min_motions) {
    return Failed(r, Termination::kInsufficientMotion,
                  "need >= " + std::to_string(options.min_motions) + " consistent motions, got " +
                      std::to_string(used) + " after misfit removal");
  }
  const Observability& figures = r.observability;
  const ModelSelectionOptions& select = options.model_selection;
  if (options.motion_model == MotionModel::kGeneral && !setting.translational &&
      ((figures.tilt_snr < select.min_tilt_snr &&
        figures.axis_spread_deg < select.general_axis_spread_deg) ||
       figures.axis_spread_deg < select.planar_axis_spread_deg)) {
    SlaveCalibration planar = r;
    planar.observability.planar = true;
    planar.unobservable = {figures.planar_axis};
    planar.estimate.q = linear.q;
    if (linear.pos.ok) planar.estimate.C = linear.pos.C;
    return Failed(planar, Termination::kDegenerate,
                  "planar motion (the rotation axes tilt no more than rotation noise explains: "
                  "spread " +
                      FixedText(figures.axis_spread_deg, 3) + " deg, tilt SNR " +
                      FixedText(figures.tilt_snr, 1) +
                      "): the rotation about the axis and C along it are not determined by the "
                      "general model; use the planar model (motion model auto or planar)");
  }
  if (!linear.pos.ok) {
    if (r.motion_model == MotionModel::kPlanar) {
      return Failed(r, Termination::kDegenerate,
                    "planar motion (" + linear.fit.solution.why +
                        "), but the in-plane translation equations are singular: the motions do "
                        "not determine the angle about the axis, position and scale");
    }
    return Failed(r, Termination::kDegenerate,
                  "the position/scale equations (4.16) are singular: the motions do not "
                  "determine position and scale");
  }
  return std::nullopt;
}

void AssembleResult(const CalibrationOptions& options, const BatchSetting& setting,
                    const std::vector<MotionData>& data, const LinearEstimate& linear,
                    const BatchRefinement& refinement, const ScaleModelChoice& scale,
                    SlaveCalibration* r) {
  const bool parallel = TakeRefinedEstimate(setting, data, linear, refinement, r);
  r->message = BatchMessage(options, setting, linear, refinement, scale, parallel, *r);
  r->termination = parallel ? Termination::kDegenerate
                   : (refinement.solved && !refinement.refined.converged)
                       ? Termination::kNoConvergence
                       : Termination::kSolved;
}

}  // namespace rigcal::internal
