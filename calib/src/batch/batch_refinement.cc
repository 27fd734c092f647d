// SPDX-License-Identifier: Apache-2.0
// The non-linear refinement of the batch calibrator (batch_refinement.h).
#include "batch/batch_refinement.h"

#include <algorithm>
#include <cmath>

#include "models/linear_solvers.h"
#include "noise/time_blocks.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {

BatchRefinement RefineBatch(const CalibrationOptions& options, const BatchSetting& setting,
                            const std::vector<MotionData>& data, const LinearEstimate& linear,
                            const Eigen::Vector3d& axis, bool planar, double epsilon) {
  const bool translational = setting.translational;
  const AxisPrior& prior = setting.prior;
  const Eigen::Quaterniond& dq = linear.q;
  const LinearPositionScale& pos = linear.pos;
  // Noise levels from the linear residuals whiten the non-linear problem.
  const int num_scales = static_cast<int>(linear.scale_keys.size());
  const int k = static_cast<int>(data.size());
  double ss_rot = 0.0, ss_pos = 0.0, typical = 0.0;
  for (const auto& m : data) {
    const double s = pos.scales[m.scale_index];
    if (!translational) ss_rot += std::pow(RotationResidual(m, ToWxyz(dq)), 2);
    ss_pos += std::pow(
        translational ? TranslationalResidual(m, dq, s) : PositionResidual(m, dq, pos.C, s), 2);
    typical = std::max(typical, m.C0.norm());
  }
  RefinementInput input;
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
  // (The general model without a weighted prior keeps C a plain 3-vector.)
  const bool weighted_prior = prior.given && prior.sigma > 0.0;
  if (!translational && axis.norm() > 0.5 && (planar || weighted_prior)) {
    input.axis = axis;
    input.axis_prior = setting.AxisPriorAlong(axis);
    input.axis_prior_sigma = prior.given ? prior.sigma : 0.0;
    // Planar: nothing but the prior determines h, so it is held at the prior's value (or 0).
    input.axis_offset_fixed = planar;
  }

  BatchRefinement out;
  const auto measurements = MeasureScales(data, epsilon, translational);
  for (int s = 0; s < num_scales; ++s) {
    out.summaries.push_back(SummarizeScales(measurements, data, s));
    // Prior of (4.27), σ² = sum (λ - λ^k)² as in the thesis; none for planar motion, whose
    // measurements (4.18) are ratios of noise (translation perpendicular to the axis).
    const ScaleSummary& summary = out.summaries[s];
    input.priors.push_back(
        {summary.mean, summary.count >= 2 && !planar ? summary.sigma_thesis : 0.0});
  }

  const int blocks = BlocksForDurations(data, options.covariance_time_blocks);
  if (blocks > 0 && k >= 4 * blocks) {
    input.blocks = TimeBlocks(data, blocks);
    out.time_blocks = blocks;
  }
  out.solved = options.method == Method::kNonlinear;
  out.refined = RefineNonlinear(data, input, options, out.solved);
  return out;
}

}  // namespace rigcal::internal
