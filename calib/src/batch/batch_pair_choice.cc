// SPDX-License-Identifier: Apache-2.0
// Per-slave span choice by the σ a fitted drift model predicts (batch_pair_choice.h).
#include "batch/batch_pair_choice.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "batch/batch_result.h"
#include "batch/batch_solve_details.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/rig_calibrator.h"

namespace rigcal::internal {
namespace {

struct Candidate {
  int span = 0;       // relative:N, 0 for the walk
  double frames = 0;  // the median span of the pairs, in poses
  SlaveCalibration result;
  SlaveSolveDetails details;
};

// Variances the candidates are compared by (rotation: largest axis, deg²; position: trace of C's
// covariance across the rotation axis when `in_plane`, master units²), reported and of
// independent motions. NaN when unknown or zero (a zero σ says nothing).
struct Variances {
  double rot = std::numeric_limits<double>::quiet_NaN();
  double pos = std::numeric_limits<double>::quiet_NaN();
  double rot_independent = std::numeric_limits<double>::quiet_NaN();
  double pos_independent = std::numeric_limits<double>::quiet_NaN();
};

double Comparable(double variance) {
  return std::isfinite(variance) && variance > 0.0 ? variance
                                                   : std::numeric_limits<double>::quiet_NaN();
}

double LargestEigenvalue(const Eigen::Matrix3d& m) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues()(2);
}

Variances VariancesOf(const Candidate& c, bool in_plane) {
  Variances v;
  const SlaveCalibration& r = c.result;
  if (!r.solved() || !c.details.covariance_ok) return v;
  const double deg2 = kDegPerRad * kDegPerRad;
  v.rot = Comparable(LargestEigenvalue(c.details.cov_rotation) * deg2);
  v.rot_independent = Comparable(LargestEigenvalue(c.details.independent_cov_rotation) * deg2);
  if (!r.position_observable) return v;
  Eigen::Matrix3d across = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d& axis = r.observability.planar_axis;
  if (in_plane && axis.norm() > 0.5) across -= axis.normalized() * axis.normalized().transpose();
  v.pos = Comparable((across * c.details.cov_position * across).trace());
  v.pos_independent = Comparable((across * c.details.independent_cov_position * across).trace());
  return v;
}

Candidate Solve(const RigRecording& recording, int slave, const CalibrationOptions& options,
                const PairOptions& policy, const std::vector<IndexPair>& pairs) {
  Candidate c;
  c.span = policy.policy == PairOptions::Policy::kRelative ? policy.step : 0;
  std::vector<double> spans;
  spans.reserve(pairs.size());
  for (const IndexPair& p : pairs) spans.push_back(p.b - p.a);
  c.frames = spans.empty() ? 0.0 : Median(spans);
  c.result = CalibrateSlave(MotionsForSlave(recording, slave, pairs), options,
                            recording.slaves[slave].name, &c.details);
  c.result.pairs = PairsText(policy);
  return c;
}

// Errors shared by overlapping motions (odometry drift) make the variance of an estimate from
// motions N poses long larger than that of independent motions by the design effect
// (1 + ρN²) / (1 + ρN), ρ the drift variance per pose over the white part: N motions share each
// drift step (the cluster-robust covariance measures the effect, refinement.h).
double DesignEffect(double frames, double rho) {
  return (1.0 + rho * frames * frames) / (1.0 + rho * frames);
}

// ρ and a level common to every span (errors of unequal size raise every span's measured
// effect alike) fitted to the candidates' measured design effects (reported over independent
// variance, in logarithms, each weighted by the degrees of freedom of its cluster-robust
// estimate, the time blocks - 1): the measured effect of a single span is itself noisy (few
// blocks for long spans), the fit pools every span's.
struct DriftFit {
  double rho = 0.0;
  double level = 1.0;  // the design effect's factor common to every span
};
DriftFit FitDrift(const std::vector<Candidate>& candidates, const std::vector<double>& reported,
                  const std::vector<double>& independent) {
  DriftFit best;
  double best_cost = std::numeric_limits<double>::infinity();
  for (int step = -1; step <= 200; ++step) {
    const double rho = step < 0 ? 0.0 : std::pow(10.0, -8.0 + 0.05 * step);
    double sum_w = 0.0, sum_wm = 0.0, sum_wmm = 0.0;
    for (size_t k = 0; k < candidates.size(); ++k) {
      const int blocks = candidates[k].details.time_blocks;
      if (candidates[k].span == 0 || blocks < 2 || !std::isfinite(reported[k]) ||
          !std::isfinite(independent[k])) {
        continue;
      }
      const double misfit = std::log(reported[k] / independent[k]) -
                            std::log(DesignEffect(candidates[k].frames, rho));
      sum_w += blocks - 1;
      sum_wm += (blocks - 1) * misfit;
      sum_wmm += (blocks - 1) * misfit * misfit;
    }
    if (sum_w <= 0.0) return best;
    const double mean = sum_wm / sum_w;
    const double cost = sum_wmm - 2.0 * mean * sum_wm + mean * mean * sum_w;
    if (cost < best_cost) {
      best_cost = cost;
      best = {rho, std::exp(mean)};
    }
  }
  return best;
}

// Per candidate, the variance predicted by the drift model: the independent motions' variance
// times the fitted design effect. The walk (spans of every length, overlapping unlike a fixed
// span's) and candidates without a cluster-robust estimate keep the reported variance.
std::vector<double> Predicted(const std::vector<Candidate>& candidates,
                              const std::vector<double>& reported,
                              const std::vector<double>& independent) {
  const DriftFit fit = FitDrift(candidates, reported, independent);
  std::vector<double> out = reported;
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (candidates[k].span > 0 && std::isfinite(independent[k]) &&
        candidates[k].details.time_blocks >= 2) {
      out[k] = independent[k] * fit.level * DesignEffect(candidates[k].frames, fit.rho);
    }
  }
  return out;
}

// The candidate whose worse predicted σ ratio to the best (rotation, and position where every
// candidate has one) is smallest (-1 when none has a comparable rotation σ), and the candidates
// of the smallest predicted rotation and position σ (-1 when none).
struct Ranking {
  int best = -1;
  int rotation = -1;
  int position = -1;
};
Ranking Rank(const std::vector<Candidate>& candidates, bool usable_only) {
  auto eligible = [&](const Candidate& c) {
    return c.result.solved() && (!usable_only || c.result.usable());
  };
  // Position σ compare across the rotation axis when any span's motions are planar (the
  // offset along the axis is then the nominal's or unknown, not what the span determines).
  bool in_plane = false;
  for (const auto& c : candidates) {
    if (eligible(c) && c.result.motion_model == MotionModel::kPlanar) in_plane = true;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> rot(candidates.size(), nan), pos(candidates.size(), nan);
  std::vector<double> rot_independent = rot, pos_independent = pos;
  bool every_pos = true;
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (!eligible(candidates[k])) continue;
    const Variances v = VariancesOf(candidates[k], in_plane);
    rot[k] = v.rot;
    pos[k] = v.pos;
    rot_independent[k] = v.rot_independent;
    pos_independent[k] = v.pos_independent;
    if (std::isfinite(rot[k]) && !std::isfinite(pos[k])) every_pos = false;
  }
  rot = Predicted(candidates, rot, rot_independent);
  pos = Predicted(candidates, pos, pos_independent);
  Ranking out;
  double rot_min = std::numeric_limits<double>::infinity();
  double pos_min = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (std::isfinite(rot[k]) && rot[k] < rot_min) {
      rot_min = rot[k];
      out.rotation = static_cast<int>(k);
    }
    if (std::isfinite(rot[k]) && std::isfinite(pos[k]) && pos[k] < pos_min) {
      pos_min = pos[k];
      out.position = static_cast<int>(k);
    }
  }
  double best_score = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (!std::isfinite(rot[k])) continue;
    double score = rot[k] / rot_min;
    if (every_pos && std::isfinite(pos_min)) score = std::max(score, pos[k] / pos_min);
    if (score < best_score) {
      best_score = score;
      out.best = static_cast<int>(k);
    }
  }
  return out;
}

}  // namespace

AutoPairCandidates MakeAutoPairCandidates(const RigRecording& recording,
                                          const PairOptions& options) {
  AutoPairCandidates out;
  const int n = static_cast<int>(recording.size());
  out.stride = std::max(1, (n + options.max_pairs - 1) / options.max_pairs);
  for (int span : AutoSpanCandidates(n, options)) {
    PairOptions relative = options;
    relative.policy = PairOptions::Policy::kRelative;
    relative.step = span;
    out.policies.push_back(relative);
    out.pairs.push_back(RelativePairs(recording, span, out.stride));
  }
  // The walk: a span per anchor that reaches a large rotation (hand-held recordings with
  // pauses, where any fixed span often spans no rotation at all).
  PairOptions walk = options;
  walk.policy = PairOptions::Policy::kWalk;
  out.policies.push_back(walk);
  out.pairs.push_back(SelectPairs(recording, walk));
  return out;
}

SlaveCalibration CalibrateSlaveAutoPairs(const RigRecording& recording,
                                         const AutoPairCandidates& choices, int slave,
                                         const CalibrationOptions& options,
                                         AutoPairRanking* ranking) {
  std::vector<Candidate> candidates;
  candidates.reserve(choices.policies.size());
  for (size_t k = 0; k < choices.policies.size(); ++k) {
    if (options.cancelled()) {
      SlaveCalibration cancelled;
      cancelled.name = recording.slaves[slave].name;
      return Failed(cancelled, Termination::kCancelled, "cancelled");
    }
    candidates.push_back(Solve(recording, slave, options, choices.policies[k], choices.pairs[k]));
  }

  Ranking ranked = Rank(candidates, true);
  if (ranked.best < 0) ranked = Rank(candidates, false);
  int best = ranked.best;
  std::string how;
  if (best < 0) {
    // No candidate has a σ: the one with the most motions used says best what is missing.
    best = 0;
    for (size_t k = 1; k < candidates.size(); ++k) {
      if (candidates[k].result.motions.used > candidates[best].result.motions.used) {
        best = static_cast<int>(k);
      }
    }
    how = "no span gave a σ";
  } else {
    how = "smallest σ predicted by the drift fit among spans " +
          std::to_string(candidates.front().span) + "-" +
          std::to_string(candidates[candidates.size() - 2].span) + " and the walk";
  }
  // A thinned span is solved again with every k.
  auto full = [&](int k) {
    if (choices.stride > 1 && candidates[k].span > 0) {
      return Solve(recording, slave, options, choices.policies[k],
                   RelativePairs(recording, candidates[k].span));
    }
    return candidates[k];
  };
  Candidate chosen = full(best);
  if (ranking != nullptr && ranked.rotation >= 0 && ranked.position >= 0 &&
      ranked.rotation != ranked.position) {
    ranking->rotation = ranked.rotation == best ? chosen.result : full(ranked.rotation).result;
    ranking->position = ranked.position == best ? chosen.result : full(ranked.position).result;
    ranking->differ = true;
  }
  SlaveCalibration r = std::move(chosen.result);
  // A motion model given in the options must hold on every span: a span whose solve finds the
  // data contradicting it (batch_acceptance.h) makes the result not usable, however well the
  // model fits the chosen span's (shorter) motions.
  // The longest such span is named: its motions show the contradiction most clearly.
  if (options.motion_model != MotionModel::kAuto && r.contradiction.empty()) {
    const Candidate* worst = nullptr;
    for (const Candidate& c : candidates) {
      if (!c.result.contradiction.empty() && (worst == nullptr || c.span > worst->span)) {
        worst = &c;
      }
    }
    if (worst != nullptr) {
      r.state = SlaveState::kInitialising;
      r.contradiction = worst->result.contradiction;
      r.message = "not usable: on the motions of pairs " + worst->result.pairs + ": " +
                  worst->result.contradiction + "; " + r.message;
    }
  }
  r.message += "; pairs " + r.pairs + " (auto: " + how + ")";
  ModuleLogger("calib")->debug("slave '{}': auto pairs {} ({})", r.name, r.pairs, how);
  return r;
}

}  // namespace rigcal::internal
