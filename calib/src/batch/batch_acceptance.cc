// SPDX-License-Identifier: Apache-2.0
// Whether the data support the batch (and online) estimate (batch_acceptance.h).
#include "batch/batch_acceptance.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>

#include "models/model_explanation.h"
#include "motions/non_finite.h"
#include "rigcal/base/format.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {
namespace {

// Median of the χ² distribution with 3 degrees of freedom.
constexpr double kChi2Median3 = 2.366;
// 99.9 % quantile of χ² with 3 degrees of freedom.
constexpr double kChi2Quantile3 = 16.27;
// Rotation noise below this is numerical (noise-free data): the test's floor, degrees.
constexpr double kNoiseFloorDeg = 1e-6;
// The pairing tests' least ratio of the shifted to the actual residual scale.
constexpr double kPairingLimit = 3.0;
// Least number of independent motions: two determine a rotating rig exactly; the residual test
// needs redundancy and the pairing tests four motions.
constexpr int kMinIndependent = 4;
// Least motions before the online estimator's pairing tests decide: the estimate is fitted to
// the same motions (4 to 7 parameters), and on fewer motions that fit alone can make the actual
// pairing look 3 times better than a shifted one (measured: unrelated random trajectories
// passed at 20 motions).
constexpr int kMinOnlinePairing = 30;
// Largest σ of a determined rotation (degrees) and scale (fraction of the scale).
constexpr double kMaxRotationStdDeg = 10.0;
constexpr double kMaxScaleStdFraction = 0.5;

int Find(std::vector<int>* parent, int i) {
  while ((*parent)[i] != i) {
    (*parent)[i] = (*parent)[(*parent)[i]];
    i = (*parent)[i];
  }
  return i;
}

// Parameters of the model: rotation 3, C 3 (general), 2 (planar: in-plane) or 0
// (translational), one per scale.
int ParameterCount(const SlaveCalibration& r) {
  const int position = r.motion_model == MotionModel::kTranslational ? 0
                       : r.motion_model == MotionModel::kPlanar      ? 2
                                                                     : 3;
  return 3 + position + static_cast<int>(std::max<size_t>(r.scales.size(), 1));
}

// Equations an independent motion contributes: a rotating rig 2 on the rotation (the axis;
// the angle is the same on both sides whatever the extrinsics) and 3 on the position
// (4.14); the translational model 3 (the translation, 4.29).
int EquationsPerMotion(const SlaveCalibration& r) {
  return r.motion_model == MotionModel::kTranslational ? 3 : 5;
}

// Motion order by time, for the shifted pairings.
std::vector<size_t> TimeOrder(const std::vector<MotionData>& motions) {
  std::vector<size_t> order(motions.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return motions[a].t_ns < motions[b].t_ns; });
  return order;
}

std::string RotationReason(const RotationConsistency& rot, MotionModel model) {
  if (!rot.related) {
    return "the trajectories are unrelated: the rotation residual " +
           FixedText(rot.residual_deg, 3) +
           " deg per axis (robust) is hardly smaller than with the master's motions of other "
           "times (" +
           FixedText(rot.pairing_ratio, 2) + "x, need >= " + FixedText(rot.pairing_limit, 1) +
           "x): the cameras do not rotate together as one rig";
  }
  return "residuals inconsistent with the measured noise: rotation residual " +
         FixedText(rot.residual_deg, 3) + " deg per axis (robust) is " + FixedText(rot.ratio, 1) +
         "x the rotation noise " + FixedText(rot.noise_deg, 3) +
         " deg measured from the master-slave rotation angles (limit " + FixedText(rot.limit, 2) +
         "x): the trajectories do not move as one rig under the " + ToString(model) + " model";
}

std::string TranslationReason(const TranslationPairing& t) {
  return "the translations are unrelated: the translational model's residual " +
         SignificantText(t.residual, 3) +
         " is hardly smaller than with the master's motions of other times (" +
         FixedText(t.ratio, 2) + "x, need >= " + FixedText(t.limit, 1) +
         "x): a stationary rig, or the cameras do not move together";
}

// λ per motion: the scale whose key (`by_segment`: segment id, else scale key) the motion has,
// else `fallback`.
std::vector<double> ScalesOf(const std::vector<MotionData>& motions,
                             const std::vector<SegmentScale>& scales, bool by_segment,
                             double fallback) {
  std::map<int, double> by_key;
  for (const SegmentScale& seg : scales) by_key[seg.segment] = seg.scale;
  std::vector<double> out;
  out.reserve(motions.size());
  for (const MotionData& m : motions) {
    const auto it = by_key.find(by_segment ? m.segment : m.scale_key);
    out.push_back(it != by_key.end() ? it->second : fallback);
  }
  return out;
}

}  // namespace

int IndependentMotions(const std::vector<MotionData>& motions) {
  std::map<int64_t, int> index;
  for (const auto& m : motions) {
    index.emplace(m.t_a_ns, static_cast<int>(index.size()));
    index.emplace(m.t_b_ns, static_cast<int>(index.size()));
  }
  std::vector<int> parent(index.size());
  std::iota(parent.begin(), parent.end(), 0);
  int rank = 0;
  for (const auto& m : motions) {
    const int a = Find(&parent, index.at(m.t_a_ns));
    const int b = Find(&parent, index.at(m.t_b_ns));
    if (a == b) continue;  // closes a cycle: implied by the motions before
    parent[a] = b;
    ++rank;
  }
  return rank;
}

// The consistency test. Each motion k gives the residual rotation E_k = dq⁻¹ q0_k dq qi_k⁻¹
// (the rotation-only form of q0·dq − dq·qi = 0, eq. 4.9), of angle δ_k. With isotropic rotation
// noise of σ per axis and per motion, δ_k is a 3-vector of N(0, σ²) components (two are fitted
// by dq, which costs 3 of the 2K equations, negligible for K ≫ 3), so
//     δ_k² / σ² ~ χ²(3).
// σ is measured without the extrinsics from the same motions: the master-minus-slave rotation
// angle differences θ0_k − θi_k, the component of δ_k along the rotation axis, whose robust σ
// is ε (Observability::rotation_noise_deg). The robust residual scale
//     s = sqrt(median_k δ_k² / median(χ²(3)))
// estimates σ from all three components. Consistent: s / max(ε, floor) ≤ F (1 + 3.5 / √m)
// with
//     F = 2 sqrt(χ²₃(0.999) / 3) ≈ 4.66,
// the 99.9 % bound of a single motion's per-axis residual, doubled, and m the independent
// motions: s and ε are robust scales of m effective samples each, of relative σ ≈ 1.2 / √m,
// whose ratio the second factor allows 3 of those σ (4 motions: 2.75, 100: 1.35, 1000: 1.11).
// The median (not the sum)
// and the factor make the test robust to what a plain χ² test over K motions would reject
// on good data: overlapping pairs (their residuals are correlated, the effective dof far
// below K), drifting odometry, anisotropic noise, and misfit removal. A model the data
// contradict (the translational model on a rotating rig) leaves residuals far beyond it.
//
// The pairing test. ε is measured from the same two trajectories, so two unrelated
// trajectories pass the consistency test with an ε as large as their rotations. Rigidly
// mounted cameras rotate together: pairing the slave's motion k with the master's motion of
// another time must fit far worse than the actual pairing. With s_j the robust residual scale
// of the master's motions shifted by j = K/4, K/2, 3K/4 places in time order (the same dq):
//     max_j s_j / max(s, floor) ≥ 3;
// a factor 3 in the residual scale is 9 in χ², far beyond what chance gives when the rotations
// differ by more than their noise. Only for a rotating rig (the translational model's
// rotations are noise themselves).
RotationConsistency TestRotationResiduals(const std::vector<MotionData>& motions,
                                          const Eigen::Quaterniond& q, bool rotating,
                                          int independent) {
  RotationConsistency out;
  out.limit = 2.0 * std::sqrt(kChi2Quantile3 / 3.0) *
              (1.0 + 3.5 / std::sqrt(static_cast<double>(std::max(independent, 1))));
  out.pairing_limit = kPairingLimit;
  const size_t n = motions.size();
  if (n < 2) return out;
  const Eigen::Quaterniond dq = q.normalized();
  const std::vector<size_t> order = TimeOrder(motions);
  // Robust per-axis residual scale with master motion order[(k + shift) % n] against slave
  // motion order[k].
  const auto residual_scale = [&](size_t shift) {
    std::vector<double> residual2;
    residual2.reserve(n);
    for (size_t k = 0; k < n; ++k) {
      const MotionData& master = motions[order[(k + shift) % n]];
      const MotionData& slave = motions[order[k]];
      const Eigen::Quaterniond q0 = FromWxyz(master.q0).normalized();
      const Eigen::Quaterniond qi = FromWxyz(slave.qi).normalized();
      const double d = AngleBetween(dq.conjugate() * q0 * dq, qi) * kDegPerRad;
      residual2.push_back(d * d);
    }
    return std::sqrt(MedianAndSigma(residual2).median / kChi2Median3);
  };
  std::vector<double> angle_diff;
  angle_diff.reserve(n);
  for (const auto& m : motions) angle_diff.push_back((m.angle0 - m.anglei) * kDegPerRad);
  out.noise_deg = MedianAndSigma(angle_diff).sigma;
  out.residual_deg = residual_scale(0);
  out.ratio = out.residual_deg / std::max(out.noise_deg, kNoiseFloorDeg);
  out.consistent = out.ratio <= out.limit;
  if (rotating && n >= 4) {
    double shifted = 0.0;
    for (size_t shift : {n / 4, n / 2, 3 * n / 4}) {
      shifted = std::max(shifted, residual_scale(shift));
    }
    out.pairing_ratio = shifted / std::max(out.residual_deg, kNoiseFloorDeg);
    out.related = out.pairing_ratio >= out.pairing_limit;
  }
  return out;
}

// The translational model (eq. 4.29) predicts the master's translation from the slave's:
// C0_k = λ dR Ci_k. Pairing test as for the rotations: the median residual |C0 − λ dR Ci| with
// the master's motions shifted by K/4, K/2, 3K/4 places must be at least 3 times the actual
// one. A stationary rig (translations that are noise) or unrelated trajectories fail it.
TranslationPairing TestTranslationPairing(const std::vector<MotionData>& motions,
                                          const Eigen::Quaterniond& q,
                                          const std::vector<double>& scales) {
  TranslationPairing out;
  out.limit = kPairingLimit;
  const size_t n = motions.size();
  if (n < 4 || scales.size() != n) return out;
  const std::vector<size_t> order = TimeOrder(motions);
  const Eigen::Matrix3d dr = q.normalized().toRotationMatrix();
  const auto median_residual = [&](size_t shift) {
    std::vector<double> residual;
    residual.reserve(n);
    for (size_t k = 0; k < n; ++k) {
      const size_t slave = order[k];
      const MotionData& master = motions[order[(k + shift) % n]];
      residual.push_back((master.C0 - scales[slave] * dr * motions[slave].Ci).norm());
    }
    return MedianAndSigma(residual).median;
  };
  out.residual = median_residual(0);
  double shifted = 0.0;
  for (size_t shift : {n / 4, n / 2, 3 * n / 4})
    shifted = std::max(shifted, median_residual(shift));
  out.ratio = out.residual > 0.0 ? shifted / out.residual : (shifted > 0.0 ? kInf : 0.0);
  out.related = out.ratio >= out.limit;
  return out;
}

std::optional<std::string> UndeterminedReason(const SlaveCalibration& r) {
  if (std::isfinite(r.rot_std_deg) && r.rot_std_deg > kMaxRotationStdDeg) {
    return "the rotation is not determined: sigma " + FixedText(r.rot_std_deg, 1) + " deg > " +
           FixedText(kMaxRotationStdDeg, 0) + " deg";
  }
  const std::string part = r.scales.size() > 1 ? "part " : "segment ";
  for (const SegmentScale& seg : r.scales) {
    if (std::isfinite(seg.std) && seg.std > kMaxScaleStdFraction * std::abs(seg.scale)) {
      return "the scale of " + part + std::to_string(seg.segment) + " is not determined: sigma " +
             SignificantText(seg.std, 3) + " for " + SignificantText(seg.scale, 4) + " (> " +
             FixedText(100.0 * kMaxScaleStdFraction, 0) + " %)";
    }
    // A scale maps the slave's unit to the master's: positive by definition. A fit with a
    // negative one has explained the motions with the wrong rotation.
    if (!(seg.scale > 0.0)) {
      return "the scale of " + part + std::to_string(seg.segment) + " is " +
             SignificantText(seg.scale, 4) +
             " (a scale is positive): the motions do not determine the rotation";
    }
  }
  if (r.scales.empty() && std::isfinite(r.estimate.scale) && !(r.estimate.scale > 0.0)) {
    return "the scale is " + SignificantText(r.estimate.scale, 4) +
           " (a scale is positive): the motions do not determine the rotation";
  }
  return std::nullopt;
}

std::optional<std::string> UnsupportedReason(const CalibrationOptions& options,
                                             const BatchSetting& setting,
                                             const std::vector<MotionData>& motions,
                                             const SlaveCalibration& r, bool* contradiction) {
  (void)setting;
  if (contradiction != nullptr) *contradiction = false;
  // 1. Independent motions: K independent motions give e K equations (EquationsPerMotion)
  // for p parameters; the model needs e K ≥ 2 p (as many redundant equations as parameters,
  // for the residual test) and K ≥ kMinIndependent.
  const int independent = IndependentMotions(motions);
  const int params = ParameterCount(r);
  const int per_motion = EquationsPerMotion(r);
  const int needed = std::max(kMinIndependent, (2 * params + per_motion - 1) / per_motion);
  if (independent < needed) {
    return "too few independent motions: " + std::to_string(independent) + " (of " +
           std::to_string(motions.size()) +
           " motions, sharing poses), need >= " + std::to_string(needed) + " for the " +
           std::to_string(params) + " parameters of the " + ToString(r.motion_model) + " model";
  }

  // 2. Rotation residuals against the measured rotation noise, and the pairing tests.
  const bool rotating = r.motion_model != MotionModel::kTranslational;
  const RotationConsistency rot =
      TestRotationResiduals(motions, r.estimate.q, rotating, independent);
  if (contradiction != nullptr) *contradiction = true;  // until the tests below pass
  if (!rot.related || !rot.consistent) return RotationReason(rot, r.motion_model);
  if (!rotating) {
    const TranslationPairing t = TestTranslationPairing(
        motions, r.estimate.q, ScalesOf(motions, r.scales, false, r.estimate.scale));
    if (!t.related) return TranslationReason(t);
  }

  // 3. The planar model assumes every rotation about one axis: contradicted when the master's
  // rotation axes tilt away from the mean axis by far more than rotation noise explains (tilt
  // SNR, Observability::tilt_snr, ≥ 10 max(min_tilt_snr, 1): the model selection's "clearly
  // general" level, model_selection.cc).
  const double clearly_tilting = 10.0 * std::max(options.model_selection.min_tilt_snr, 1.0);
  if (r.motion_model == MotionModel::kPlanar && r.observability.tilt_snr >= clearly_tilting) {
    return "the data contradict the planar model: the rotation axes tilt " +
           FixedText(r.observability.tilt_snr, 1) +
           "x more than rotation noise explains (>= " + FixedText(clearly_tilting, 0) +
           "x; spread " + FixedText(r.observability.axis_spread_deg, 2) +
           " deg), the motion is not about one axis; use the general model (motion model auto "
           "or general)";
  }
  if (contradiction != nullptr) *contradiction = false;

  // 4. Every parameter determined.
  return UndeterminedReason(r);
}

std::optional<std::string> OnlineUnsupportedReason(const std::vector<MotionData>& window,
                                                   const SlaveCalibration& published) {
  if (std::isinf(published.rot_std_deg)) {
    return "the rotation is not determined (the translations are all parallel)";
  }
  // A window emptied while the statistics keep their motions (a restored state file, a master
  // re-initialisation): the motions were tested while in the window; untestable until it
  // refills.
  const size_t in_window = window.size();
  if (in_window < static_cast<size_t>(kMinOnlinePairing) &&
      static_cast<size_t>(published.motions.used) > in_window) {
    return std::nullopt;
  }
  const int independent = IndependentMotions(window);
  if (independent < kMinIndependent) {
    return "too few independent motions: " + std::to_string(independent) +
           " in the window, need >= " + std::to_string(kMinIndependent);
  }
  // The first motions of a stream: the pairing tests need kMinOnlinePairing motions before
  // chance is unlikely to pass them.
  if (window.size() < static_cast<size_t>(kMinOnlinePairing)) {
    return std::to_string(window.size()) +
           " motions, need >= " + std::to_string(kMinOnlinePairing) +
           " to test that the cameras move together";
  }
  if (published.motion_model != MotionModel::kTranslational) {
    const RotationConsistency rot =
        TestRotationResiduals(window, published.estimate.q, true, independent);
    if (!rot.related || !rot.consistent) return RotationReason(rot, published.motion_model);
    return std::nullopt;
  }
  const TranslationPairing t =
      TestTranslationPairing(window, published.estimate.q,
                             ScalesOf(window, published.scales, true, published.estimate.scale));
  if (!t.related) return TranslationReason(t);
  return std::nullopt;
}

}  // namespace rigcal::internal
