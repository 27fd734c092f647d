// SPDX-License-Identifier: Apache-2.0
// Motion- and scale-model selection of the batch calibrator (batch_model_selection.h).
#include "batch/batch_model_selection.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "models/model_explanation.h"
#include "models/scale_measurement.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/calib/error_model.h"

namespace rigcal::internal {
namespace {

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

int CountSegments(const std::vector<MotionData>& motions) {
  std::map<int, int> seen;
  for (const auto& m : motions) seen[m.segment]++;
  return static_cast<int>(seen.size());
}

// Thesis 5.5: measured scales (4.18 / 4.31) that drift by more than the threshold (and by
// more than their own noise) call for time-dependent scales. Returns the partition count
// (1 = time-fixed).
// Planar motion translates perpendicular to the rotation axis, so the measurements of (4.18)
// are ratios of noise: the drift is tested with the position equations alone.
int ChoosePartitions(const std::vector<MotionData>& motions, double epsilon, bool translational,
                     bool planar, const CalibrationOptions& options, const BatchSetting& setting,
                     std::string* why) {
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
    const std::vector<double> scales = SolveScales(&sorted, n, setting);
    double worst = 0.0;
    if (!scales.empty()) {
      const double center = MedianAndSigma(scales).median;
      for (double v : scales) worst = std::max(worst, std::abs(v - center) / std::abs(center));
    }
    if (worst > options.scale_deviation_threshold) {
      *why =
          "time-dependent scale: the position equations give partition scales deviating by "
          "up to " +
          FixedText(100 * worst, 1) + " % (threshold " +
          FixedText(100 * options.scale_deviation_threshold, 1) + " %)";
      return parts;
    }
    *why = "time-fixed scale: the position equations give partition scales within " +
           FixedText(100 * worst, 2) + " %";
    return 1;
  }
  const auto measurements = MeasureScales(sorted, epsilon, translational);
  const int count = static_cast<int>(measurements.size());
  const int parts = std::min(10, count / options.min_motions_per_partition);
  if (parts < 2) {
    *why = "time-fixed scale (" + std::to_string(count) +
           " scale measurements, too few to test drift)";
    return 1;
  }
  std::vector<double> all;
  for (const auto& m : measurements) all.push_back(m.value);
  const double overall = MedianAndSigma(all).median;
  double worst = 0.0;
  bool significant = false;
  for (int p = 0; p < parts; ++p) {
    const int lo = p * count / parts, hi = (p + 1) * count / parts;
    std::vector<double> v;
    for (int k = lo; k < hi; ++k) v.push_back(measurements[k].value);
    const auto stats = MedianAndSigma(v);
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
    const std::vector<double> scales = SolveScales(&work, n, setting);
    double lls_worst = 0.0;
    if (!scales.empty()) {
      std::vector<double> sorted_scales = scales;
      const double center = MedianAndSigma(sorted_scales).median;
      for (double v : scales)
        lls_worst = std::max(lls_worst, std::abs(v - center) / std::abs(center));
    }
    if (lls_worst > options.scale_deviation_threshold) {
      *why = "time-dependent scale: scales deviate by up to " + FixedText(100 * lls_worst, 1) +
             " % over time (threshold " + FixedText(100 * options.scale_deviation_threshold, 1) +
             " %)";
      return parts;
    }
    *why = "time-fixed scale: measured scales (4.18) vary by up to " + FixedText(100 * worst, 1) +
           " %, but the position equations give partition scales within " +
           FixedText(100 * lls_worst, 1) + " %";
    return 1;
  }
  *why = "time-fixed scale: measured scales deviate by at most " + FixedText(100 * worst, 1) + " %";
  return 1;
}

}  // namespace

BatchSetting SelectMotionModel(const CalibrationOptions& options, const std::string& name,
                               const std::vector<MotionData>& data, Observability* figures) {
  double max_rotation = 0.0;
  for (const auto& m : data) max_rotation = std::max(max_rotation, m.angle0);
  figures->max_rotation_deg = max_rotation * kDegPerRad;

  // Thesis 5.2: the purely translational model below the equal-error boundary, which scales
  // with the measured rotation noise (model_selection.h).
  figures->rotation_noise_deg = RotationNoiseDeg(data);
  figures->translational_below_deg = TranslationalBelowDeg(
      options.model_selection.alpha_maxrot_deg, options.model_selection.alpha_maxrot_noise_deg,
      figures->rotation_noise_deg, options.alpha_threshold_deg);
  BatchSetting setting;
  setting.requested = options.motion_model;
  if (setting.requested == MotionModel::kAuto &&
      max_rotation * kDegPerRad < figures->translational_below_deg) {
    setting.requested = MotionModel::kTranslational;
  }
  setting.translational = setting.requested == MotionModel::kTranslational;

  // What the motion cannot determine is taken from the nominal mounting, when there is one:
  // the prior on C along the mean rotation axis (its axis is known once the motions are).
  setting.select = options.model_selection;
  const auto nominal = options.nominal.find(name);
  if (nominal != options.nominal.end()) {
    setting.prior.given = true;
    setting.prior.nominal_C = nominal->second.C;
    setting.prior.sigma = options.nominal_sigma;
  }
  return setting;
}

ScaleModelChoice SelectScaleModel(const CalibrationOptions& options, const BatchSetting& setting,
                                  std::vector<MotionData>* motions) {
  const std::vector<MotionData>& data = *motions;
  const bool translational = setting.translational;
  std::vector<Eigen::Vector3d> slave_translations;
  slave_translations.reserve(data.size());
  for (const auto& m : data) slave_translations.push_back(m.Ci);
  ScaleModelChoice choice;
  choice.epsilon = ScaleDotEpsilon(options.scale_dot_epsilon, slave_translations);
  choice.model = options.scale_model;
  int partitions = options.partitions;
  if (choice.model == ScaleModel::kAuto) {
    if (CountSegments(data) > 1) {
      choice.model = ScaleModel::kSegments;
      choice.why = "one scale per odometry segment (" + std::to_string(CountSegments(data)) + ")";
    } else {
      bool planar_motion = false;
      if (!translational) {
        std::vector<MotionData> work = data;  // one scale (scale_index 0)
        planar_motion =
            SolveRotatingLinear(&work, 1, setting).solution.model == MotionModel::kPlanar;
      }
      partitions = ChoosePartitions(data, choice.epsilon, translational, planar_motion, options,
                                    setting, &choice.why);
      choice.model = partitions > 1 ? ScaleModel::kPartitions : ScaleModel::kFixed;
    }
  }
  AssignScaleKeys(choice.model, partitions, motions);
  return choice;
}

}  // namespace rigcal::internal
