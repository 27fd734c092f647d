// SPDX-License-Identifier: Apache-2.0
// The background refinement of the recursive estimator: the non-linear refinement of a slave's
// window with the prior of the motions before it, and when its outcome is published.
#include "online/window_refinement.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "batch/batch_solve_details.h"
#include "models/linear_solvers.h"
#include "motions/motion_data.h"
#include "refinement/refinement.h"
#include "refinement/statistics_prior.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/refinement_job.h"
#include "rigcal/calib/rig_calibrator.h"

namespace rigcal {
namespace {

// The batch calibrator on every set since the restart (its pair choice and σ), when the job
// holds them and it solves; else nullopt (the window refinement then).
std::optional<SlaveCalibration> RefineHistory(const RefinementJob& job) {
  if (job.history.t_ns.empty() || !job.start.solved()) return std::nullopt;
  CalibrationOptions options = job.history_options;
  options.cancel = job.cancel;
  SlaveCalibration batch = internal::CalibrateRigSlave(job.history, options, 0);
  if (!batch.solved()) return std::nullopt;  // not solvable yet
  const std::string sets =
      job.history_stride > 1
          ? std::to_string(job.history.size()) + " means of " + std::to_string(job.history_stride) +
                " consecutive sets since the start (a drive " + "longer than the history)"
          : std::to_string(job.history.size()) + " sets since the start";
  batch.message = "batch on the " + sets + ": " + batch.message;
  return batch;
}

// The refinement of the window's motions `data` (signs aligned with the start) from the job's
// start: one scale variable per segment of the window and the prior (`index`: segment ->
// variable), C about the mean rotation axis in the planar model (its offset fixed) or with a
// weighted prior along it, the prior's scale variables in `prior_scales`.
internal::RefinementInput WindowInput(const RefinementJob& job,
                                      std::vector<internal::MotionData>* data,
                                      std::map<int, int>* index,
                                      std::vector<double>* prior_scales) {
  internal::RefinementInput input;
  input.q = job.start.estimate.q;
  input.C = job.start.estimate.C;
  input.translational = job.start.motion_model == MotionModel::kTranslational;
  const bool planar = job.start.motion_model == MotionModel::kPlanar;
  const Eigen::Vector3d axis = job.start.observability.planar_axis;
  if (!input.translational && axis.norm() > 0.5 && (planar || job.axis_prior_sigma > 0.0)) {
    // The reduced parameter set: C = B p + h a, h fixed in the planar model, pulled towards
    // the nominal by a weighted term in the general model.
    input.axis = axis;
    input.axis_prior = job.axis_prior;
    input.axis_prior_sigma = job.axis_prior_sigma;
    input.axis_offset_fixed = planar;
  }
  auto scale_index = [&](int segment) {
    auto [it, inserted] = index->emplace(segment, static_cast<int>(index->size()));
    if (inserted) {
      double scale = job.start.estimate.scale;
      for (const auto& sc : job.start.scales) {
        if (sc.segment == segment) scale = sc.scale;
      }
      input.scales.push_back(scale);
    }
    return it->second;
  };
  for (auto& m : *data) m.scale_index = scale_index(m.segment);
  if (job.weights.size() == data->size()) input.weights = job.weights;
  if (job.prior.weight > 0.0) {
    input.prior = &job.prior;
    for (int segment : job.prior.segments) {
      input.prior_scale_index.push_back(scale_index(segment));
      prior_scales->push_back(input.scales[input.prior_scale_index.back()]);
    }
  }
  return input;
}

// The noise levels that whiten the refinement: from the residuals at the start, of the window's
// motions and the prior's.
void SetNoiseLevels(const RefinementJob& job, const std::vector<internal::MotionData>& data,
                    const std::vector<double>& prior_scales, internal::RefinementInput* input) {
  const bool planar = job.start.motion_model == MotionModel::kPlanar;
  double ss_rot = 0.0, ss_pos = 0.0, k = 0.0;
  for (size_t j = 0; j < data.size(); ++j) {
    const internal::MotionData& m = data[j];
    const double w = input->weights.empty() ? 1.0 : input->weights[j];
    const double s = input->scales[m.scale_index];
    ss_rot += w * std::pow(internal::RotationResidual(m, ToWxyz(input->q)), 2);
    ss_pos +=
        w * std::pow(input->translational ? internal::TranslationalResidual(m, input->q, s)
                                          : internal::PositionResidual(m, input->q, input->C, s),
                     2);
    k += w;
  }
  if (input->prior != nullptr) {
    ss_rot += internal::RotationPriorValue(job.prior, input->q);
    ss_pos += internal::PositionPriorValue(
        job.prior, input->q, input->translational ? Eigen::Vector3d::Zero() : input->C,
        prior_scales);
    k += job.prior.weight;
  }
  // The prior's position sums may hold fewer motions than its rotation's (master re-initialised).
  const double k_pos =
      input->prior != nullptr ? k - (job.prior.weight - job.prior.position_weight) : k;
  input->sigma_rotation = std::max(std::sqrt(ss_rot / std::max(1.0, 4 * k - 3)), 1e-12);
  input->sigma_position =
      std::max(std::sqrt(ss_pos / std::max(1.0, 3 * k_pos - (planar ? 6 : 7))), 1e-12);
}

// The refined estimate `r` of `input` in `out` (the job's start): rotation, C, the scales of
// the segments refined (`index`) and the current one, σ from its covariance, the termination.
void TakeRefined(const RefinementJob& job, const internal::RefinementInput& input,
                 const std::map<int, int>& index, const internal::RefinementResult& r,
                 SlaveCalibration* out) {
  const bool planar = job.start.motion_model == MotionModel::kPlanar;
  const Eigen::Vector3d axis = job.start.observability.planar_axis;
  out->estimate.q = r.q;
  if (!input.translational) out->estimate.C = r.C;
  for (auto& sc : out->scales) {
    auto it = index.find(sc.segment);
    if (it != index.end()) {
      sc.scale = r.scales[it->second];
      sc.std = r.scale_std[it->second];
    }
  }
  const int newest = !job.motions.empty()          ? job.motions.back().segment
                     : !job.prior.segments.empty() ? job.prior.segments.back()
                                                   : -1;
  const auto current = index.find(newest);
  if (current != index.end()) out->estimate.scale = r.scales[current->second];
  if (r.covariance_ok) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(r.cov_rotation);
    out->rot_std_deg = std::sqrt(std::max(0.0, eig.eigenvalues()(2))) * kDegPerRad;
    if (!input.translational) out->pos_std = r.cov_position.diagonal().cwiseMax(0.0).cwiseSqrt();
    if (!input.translational && !input.axis_offset_fixed && input.axis.norm() > 0.5) {
      out->axis_offset_std = r.axis_std;
    } else if (!input.translational && !planar && axis.norm() > 0.5) {
      out->axis_offset_std = std::sqrt(std::max(0.0, axis.dot(r.cov_position * axis)));
    } else if (planar && job.axis_prior_sigma > 0.0) {
      const Eigen::Matrix3d cov =
          r.cov_position + job.axis_prior_sigma * job.axis_prior_sigma * axis * axis.transpose();
      out->pos_std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
    }
  }
  out->termination = r.converged ? Termination::kSolved : Termination::kNoConvergence;
}

}  // namespace

SlaveCalibration RefineWindow(const RefinementJob& job) {
  if (std::optional<SlaveCalibration> batch = RefineHistory(job)) return *batch;
  SlaveCalibration out = job.start;
  if (!job.start.solved() || static_cast<int>(job.motions.size()) + job.prior.motions < 3) {
    return out;
  }
  std::vector<internal::MotionData> data = internal::ToMotionData(job.motions);
  internal::AlignSignsWith(ToWxyz(job.start.estimate.q), &data);
  std::map<int, int> index;
  std::vector<double> prior_scales;
  internal::RefinementInput input = WindowInput(job, &data, &index, &prior_scales);
  SetNoiseLevels(job, data, prior_scales, &input);
  CalibrationOptions options;
  options.robust_loss = job.robust_loss ? RobustLoss::kHuber : RobustLoss::kNone;
  options.cancel = job.cancel;
  const internal::RefinementResult r = internal::RefineNonlinear(data, input, options);
  if (!r.q.coeffs().allFinite() || !r.C.allFinite()) return out;
  TakeRefined(job, input, index, r, &out);
  return out;
}

namespace internal {

bool RefinementAgrees(const RigEstimatorOptions& o, const SlaveCalibration& refined,
                      const SlaveCalibration& linear, double rot_factor) {
  const double sigma = std::max(rot_factor * linear.rot_std_deg, 1e-3);  // shared drift counted
  return AngleBetween(refined.estimate.q, linear.estimate.q) * kDegPerRad <= o.gate_sigmas * sigma;
}

}  // namespace internal
}  // namespace rigcal
