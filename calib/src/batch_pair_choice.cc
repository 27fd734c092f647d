// Per-slave span choice by the reported σ (batch_pair_choice.h).
#include "batch_pair_choice.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "rigcal/calib/logging.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/calib/rig_calibrator.h"

namespace rigcal::internal {
namespace {

struct Candidate {
  int span = 0;
  SlaveCalibration result;
  double rot = std::numeric_limits<double>::quiet_NaN();           // rotation σ, degrees
  double pos = std::numeric_limits<double>::quiet_NaN();           // |σ_C|, master units
  double pos_in_plane = std::numeric_limits<double>::quiet_NaN();  // across the rotation axis
};

// σ that can be compared: finite and positive (an unknown or zero σ says nothing).
double Comparable(double sigma) {
  return std::isfinite(sigma) && sigma > 0.0 ? sigma : std::numeric_limits<double>::quiet_NaN();
}

Candidate Solve(const RigRecording& recording, int slave, const CalibrationOptions& options,
                const PairOptions& policy, const std::vector<IndexPair>& pairs) {
  Candidate c;
  c.span = policy.policy == PairOptions::Policy::kRelative ? policy.step : 0;
  c.result = CalibrateSlave(MotionsForSlave(recording, slave, pairs), options,
                            recording.slaves[slave].name);
  c.result.pairs = PairsText(policy);
  if (c.result.solved()) {
    c.rot = Comparable(c.result.rot_std_deg);
    if (c.result.position_observable) {
      c.pos = Comparable(c.result.pos_std.norm());
      // σ of C across the mean rotation axis: what a planar drive determines, whichever model
      // (general or planar) a span's motions call for.
      const double axis = std::isfinite(c.result.axis_offset_std) ? c.result.axis_offset_std : 0.0;
      c.pos_in_plane =
          Comparable(std::sqrt(std::max(0.0, c.result.pos_std.squaredNorm() - axis * axis)));
    }
  }
  return c;
}

// σ along the ladder of spans, smoothed: the geometric mean of each σ and its neighbours' (the
// σ of one span is itself an estimate, and the smallest of many noisy estimates is mostly the
// one that came out too small). NaN stays NaN.
std::vector<double> Smoothed(const std::vector<double>& sigma, const std::vector<bool>& ladder) {
  std::vector<double> out(sigma.size(), std::numeric_limits<double>::quiet_NaN());
  for (size_t k = 0; k < sigma.size(); ++k) {
    if (!std::isfinite(sigma[k])) continue;
    double log_sum = 0.0;
    int count = 0;
    for (size_t j = (k == 0 ? 0 : k - 1); j <= k + 1 && j < sigma.size(); ++j) {
      if (std::isfinite(sigma[j]) && (j == k || (ladder[j] && ladder[k]))) {
        log_sum += std::log(sigma[j]);
        ++count;
      }
    }
    out[k] = std::exp(log_sum / count);
  }
  return out;
}

// The candidate whose worse (smoothed) σ ratio to the best σ (rotation, and position where
// every candidate has one) is smallest; -1 when none has a comparable rotation σ.
int Best(const std::vector<Candidate>& candidates, bool usable_only) {
  auto eligible = [&](const Candidate& c) {
    return std::isfinite(c.rot) && (!usable_only || c.result.usable());
  };
  // Position σ compare across the rotation axis when any span's motions are planar (the
  // offset along the axis is then the nominal's or unknown, not what the span determines).
  bool in_plane = false;
  for (const auto& c : candidates) {
    if (eligible(c) && c.result.motion_model == MotionModel::kPlanar) in_plane = true;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> rot(candidates.size(), nan), pos(candidates.size(), nan);
  bool every_pos = true;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const Candidate& c = candidates[k];
    if (!eligible(c)) continue;
    rot[k] = c.rot;
    pos[k] = in_plane ? c.pos_in_plane : c.pos;
    if (!std::isfinite(pos[k])) every_pos = false;
  }
  std::vector<bool> ladder;
  for (const auto& c : candidates) ladder.push_back(c.span > 0);
  rot = Smoothed(rot, ladder);
  pos = Smoothed(pos, ladder);
  double rot_min = std::numeric_limits<double>::infinity();
  double pos_min = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (std::isfinite(rot[k])) rot_min = std::min(rot_min, rot[k]);
    if (std::isfinite(pos[k])) pos_min = std::min(pos_min, pos[k]);
  }
  int best = -1;
  double best_score = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (!std::isfinite(rot[k])) continue;
    double score = rot[k] / rot_min;
    if (every_pos && std::isfinite(pos_min)) score = std::max(score, pos[k] / pos_min);
    if (score < best_score) {
      best_score = score;
      best = static_cast<int>(k);
    }
  }
  return best;
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
                                         const CalibrationOptions& options) {
  std::vector<Candidate> candidates;
  candidates.reserve(choices.policies.size());
  for (size_t k = 0; k < choices.policies.size(); ++k) {
    candidates.push_back(Solve(recording, slave, options, choices.policies[k], choices.pairs[k]));
  }

  int best = Best(candidates, true);
  if (best < 0) best = Best(candidates, false);
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
    how = "smallest σ among spans " + std::to_string(candidates.front().span) + "-" +
          std::to_string(candidates[candidates.size() - 2].span) + " and the walk";
  }
  Candidate chosen = candidates[best];
  if (choices.stride > 1 && chosen.span > 0) {
    const PairOptions& policy = choices.policies[best];
    chosen = Solve(recording, slave, options, policy, RelativePairs(recording, chosen.span));
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
