// SPDX-License-Identifier: Apache-2.0
// Motion formation and misfit removal of the batch calibrator (batch_motions.h).
#include "batch/batch_motions.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "models/model_explanation.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {
namespace {

// Keeps the motions for which keep(m) is true; returns how many were removed.
template <typename Pred>
int KeepIf(std::vector<MotionData>* motions, Pred keep) {
  const size_t before = motions->size();
  motions->erase(std::remove_if(motions->begin(), motions->end(),
                                [&](const MotionData& m) { return !keep(m); }),
                 motions->end());
  return static_cast<int>(before - motions->size());
}

}  // namespace

std::vector<MotionData> FormMotions(const std::vector<RigMotion>& motions, MotionCounts* counts) {
  std::vector<MotionData> data = ToMotionData(motions);
  counts->total = static_cast<int>(data.size());
  const int non_finite = KeepIf(&data, [](const MotionData& m) {
    return m.q0.allFinite() && m.qi.allFinite() && m.C0.allFinite() && m.Ci.allFinite();
  });
  counts->residual_outlier += non_finite;
  return data;
}

int RemoveOutliers(std::vector<MotionData>* motions, const std::vector<double>& values,
                   double factor, double floor, bool two_sided) {
  const RobustStats stats = MedianAndSigma(values);
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

void RemoveUnusableMotions(const CalibrationOptions& options, bool translational,
                           std::vector<MotionData>* data, MotionCounts* counts) {
  if (!translational) {
    const double alpha = options.alpha_threshold_deg * kRadPerDeg;
    counts->small_rotation = KeepIf(
        data, [alpha](const MotionData& m) { return m.angle0 >= alpha && m.anglei >= alpha; });
  } else {
    counts->small_rotation =
        KeepIf(data, [](const MotionData& m) { return m.C0.norm() > 0.0 && m.Ci.norm() > 0.0; });
  }
  // Scale-free invariant: master and slave motions rotate by the same angle.
  std::vector<double> diff;
  for (const auto& m : *data) diff.push_back((m.angle0 - m.anglei) * kDegPerRad);
  counts->angle_mismatch = RemoveOutliers(data, diff, options.outlier_mad_factor,
                                          options.angle_invariant_floor_deg, true);
}

std::string TooFewMotionsMessage(const CalibrationOptions& options, bool translational,
                                 size_t count, double max_rotation_deg) {
  std::ostringstream msg;
  if (translational) {
    msg << "need >= " << options.min_motions << " motions with translation, got " << count;
  } else {
    msg << "need >= " << options.min_motions
        << " motions with rotation >= " << FixedText(options.alpha_threshold_deg, 1) << " deg, got "
        << count << " (largest rotation " << FixedText(max_rotation_deg, 2) << " deg)";
  }
  return msg.str();
}

}  // namespace rigcal::internal
