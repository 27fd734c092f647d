// SPDX-License-Identifier: Apache-2.0
// The linear estimate of the batch calibrator with misfit removal (batch_linear_solution.h).
#include "batch/batch_linear_solution.h"

#include <algorithm>
#include <map>

#include "batch/batch_motions.h"
#include "models/motion_statistics.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// Sums of the linear equations of the motions, one scale variable per scale_index.
MotionStatistics StatisticsOf(const std::vector<MotionData>& motions) {
  MotionStatistics stats;
  for (const auto& m : motions) stats.Add(m, m.scale_index, 1.0);
  return stats;
}

}  // namespace

RotatingFit SolveRotatingLinear(std::vector<MotionData>* motions, int num_scales,
                                const BatchSetting& setting) {
  SolveLinearRotation(motions);  // signs, incl. motions near 180 degrees
  RotatingFit fit;
  fit.solution =
      SolveRotating(StatisticsOf(*motions), setting.requested, setting.select, setting.prior);
  if (fit.solution.ok && fit.solution.rotation_from_planar) {
    std::vector<MotionData> aligned = *motions;
    AlignSignsWith(ToWxyz(fit.solution.q), &aligned);
    bool changed = false;
    for (size_t k = 0; k < aligned.size(); ++k)
      changed = changed || aligned[k].qi != (*motions)[k].qi;
    if (changed) {
      *motions = std::move(aligned);
      fit.solution =
          SolveRotating(StatisticsOf(*motions), setting.requested, setting.select, setting.prior);
    }
  }
  fit.scales.assign(num_scales, 0.0);
  for (const auto& [index, scale] : fit.solution.scales) {
    if (index >= 0 && index < num_scales) fit.scales[index] = scale;
  }
  return fit;
}

std::vector<double> SolveScales(std::vector<MotionData>* work, int n, const BatchSetting& setting) {
  if (setting.translational) return SolveTranslationalScales(*work, n);
  const RotatingFit fit = SolveRotatingLinear(work, n, setting);
  return fit.solution.ok ? fit.scales : std::vector<double>{};
}

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

LinearEstimate SolveLinear(const CalibrationOptions& options, const BatchSetting& setting,
                           std::vector<MotionData>* motions, MotionCounts* counts) {
  std::vector<MotionData>& data = *motions;
  const bool translational = setting.translational;
  LinearEstimate out;
  Eigen::Quaterniond& dq = out.q;
  LinearPositionScale& pos = out.pos;
  for (int round = 0;; ++round) {
    out.scale_keys = CompactScaleIndices(&data);
    const int num_scales = static_cast<int>(out.scale_keys.size());
    if (!translational) {
      out.fit = SolveRotatingLinear(&data, num_scales, setting);
      dq = out.fit.solution.q;
      pos.C = out.fit.solution.C;
      pos.scales = out.fit.scales;
      pos.ok = out.fit.solution.ok;
      pos.min_eigenvalue = out.fit.solution.observability.position_min_eigenvalue;
    } else {
      dq = SolveTranslationalRotation(data);
      pos.C.setZero();
      pos.scales = SolveTranslationalScales(data, num_scales);
      pos.ok = true;
    }
    if (!pos.ok || round >= options.max_outlier_rounds) break;
    std::vector<double> res_pos, res_rot;
    double typical = 0.0;
    for (const auto& m : data) {
      const double s = pos.scales[m.scale_index];
      res_pos.push_back(translational ? TranslationalResidual(m, dq, s)
                                      : PositionResidual(m, dq, pos.C, s));
      if (!translational) res_rot.push_back(RotationResidual(m, ToWxyz(dq)));
      typical = std::max(typical, m.C0.norm());
    }
    int removed =
        RemoveOutliers(&data, res_pos, options.outlier_mad_factor, 1e-9 * (1 + typical), false);
    if (!translational && removed == 0) {
      removed = RemoveOutliers(&data, res_rot, options.outlier_mad_factor, 1e-9, false);
    }
    counts->residual_outlier += removed;
    if (removed == 0) break;
    if (static_cast<int>(data.size()) < options.min_motions) break;
  }
  return out;
}

}  // namespace rigcal::internal
