// SPDX-License-Identifier: Apache-2.0
#pragma once
// One slave's estimator state inside RigEstimator (private to calib/src/online): the stages'
// states and what the published estimate rests on; rig_estimator.cc runs the stages on it,
// rig_estimator_state.cc saves and restores it.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "batch/batch_acceptance.h"
#include "models/model_explanation.h"
#include "motions/keyframe_pairing.h"
#include "online/convergence_check.h"
#include "online/decalibration_check.h"
#include "online/motion_gates.h"
#include "online/online_uncertainty.h"
#include "online/pose_history.h"
#include "online/statistics_accumulation.h"
#include "online/statistics_solution.h"
#include "online/window_refinement.h"
#include "rigcal/calib/rig_estimator.h"

namespace rigcal {

// Updates between two runs of a slave's window acceptance test (a new generation or a slave
// becoming usable runs it at once).
inline constexpr int kAcceptanceEvery = 8;

struct RigEstimator::Slave {
  explicit Slave(const RigEstimatorOptions& options) : stats(options) {}

  std::deque<internal::Keyframe> keyframes;  // keyframe_pairing
  internal::GateState gates;                 // motion_gates
  internal::DriftState drift;                // online_uncertainty
  internal::SlaveStatistics stats;           // statistics_accumulation
  internal::DecalibrationState decalibration;
  internal::ConvergenceState convergence;
  MotionCounts counts;
  GlitchCounts glitches;  // sets skipped by pose_glitch_gate
  SlaveOnlineState online;
  // The motion model: rotating once a formed motion rotated by the equal-error boundary
  // (statistics_solution.h); then general or planar, with hysteresis.
  bool rotating = false;
  bool general_model = false;
  int64_t model_changed_ns = -1;  // stream time of the last change of the motion model
  SlaveCalibration linear;        // latest linear solution of the long statistics
  std::optional<SlaveCalibration> refined;
  // The pose history (RigEstimatorOptions::history_sets): the sets since the last restart while
  // `history_complete`, merged into group means once the drive is longer than it (pose_history.h).
  using HistorySet = internal::HistorySet;
  internal::PoseHistory history;
  bool history_complete = true;
  int64_t last_history_refine_ns = std::numeric_limits<int64_t>::min();
  bool refined_from_history = false;  // `refined` is the batch calibrator's on the history
  // Restored from a state and no motion accepted since: the published estimate is the saved
  // one, and no refinement replaces it (it would refine the same information differently).
  bool restored_unchanged = false;
  // The window's acceptance test (batch_acceptance.h) costs O(window) per update: its outcome
  // is kept for kAcceptanceEvery updates of the same generation and state.
  std::optional<std::string> unsupported;
  int acceptance_age = -1;  // updates since the test; -1 = not tested
  int64_t acceptance_generation = -1;

  void RecordHistory(int capacity, uint64_t index, int64_t t_ns, const CameraPose& master,
                     const CameraPose& slave) {
    history.Record(capacity,
                   {index, t_ns, master.pose, slave.pose, master.segment, slave.segment, 1});
  }

  void RestartHistory() {
    history.Restart();
    history_complete = true;
    last_history_refine_ns = std::numeric_limits<int64_t>::min();
    refined_from_history = false;
  }

  // What the published estimate rests on beyond the statistics (SlavePublishedState).
  void SavePublished(const SlaveCalibration& published, const SlaveOnlineState& published_online,
                     SlavePublishedState* out) const {
    out->present = true;
    out->published = published;
    out->online = published_online;
    out->refined = refined;
    out->refined_from_history = refined_from_history;
    out->consecutive_angle_var = drift.consecutive_angle_var;
    out->pair_span = drift.pair_span;
    out->block_ns = stats.rotation_blocks.block_ns();
    out->blocks = stats.rotation_blocks.Save();
    out->log_decay = stats.log_decay;
    out->last_decay_ns = stats.last_decay_ns;
    out->stable = convergence.stable;
    out->last_q = convergence.last_q;
    out->glitches = glitches;
    out->decalibration = decalibration;
  }

  // The σ inflation's inputs, the forgetting clock and the glitch counts of a saved state (the
  // published estimate itself is set after the restored statistics are solved).
  void RestoreInflation(const SlavePublishedState& r) {
    if (!r.present) return;
    drift.consecutive_angle_var = r.consecutive_angle_var;
    drift.pair_span = r.pair_span;
    stats.rotation_blocks.Restore(r.block_ns, r.blocks);
    stats.log_decay = r.log_decay;
    stats.last_decay_ns = r.last_decay_ns;
    glitches = r.glitches;
  }

  // Publish's steps.
  // The linear solution of the long statistics in the motion model `choice` (general or planar
  // with hysteresis; a change of it recorded), its scales kept with the open segments'
  // statistics.
  void SolveLongWindow(const RigEstimatorOptions& o, const std::optional<Similarity>& nominal,
                       const internal::MotionModelChoice& choice) {
    const bool was_general_model = general_model;
    linear = internal::SolveStatistics(stats.long_stats, o, nominal, online.segment, choice,
                                       &general_model);
    if (rotating && general_model != was_general_model) {
      model_changed_ns = online.last_update_ns;  // general <-> planar
    }
    for (const auto& [id, segment] : stats.long_stats.segments()) {
      for (const auto& sc : linear.scales) {
        if (sc.segment == id) stats.long_stats.SetSegmentScale(id, sc.scale);
      }
    }
  }

  // Decalibration (decalibration_check.h): the short window's linear solution against the long
  // one's, counted in `decalibration`. The published rotation σ is not used for the test: after
  // a bump the time blocks disagree, which inflates that σ exactly when the windows should be
  // found to differ.
  internal::WindowComparison CompareWindows(const RigEstimatorOptions& o,
                                            const std::optional<Similarity>& nominal,
                                            const internal::MotionModelChoice& choice,
                                            const internal::SigmaInflation& inflation) {
    internal::FollowRestartedClock(online.last_update_ns, &decalibration);
    bool short_general = general_model;
    const SlaveCalibration short_est =
        linear.observability.planar
            ? SlaveCalibration{}
            : internal::SolveStatistics(stats.short_stats, o, nominal, online.segment, choice,
                                        &short_general);
    return internal::CompareWindows(
        o, linear, short_est, inflation.overlap,
        internal::ModelSettled(o, model_changed_ns, online.last_update_ns), online.last_update_ns,
        &decalibration);
  }

  // A confirmed decalibration: the estimate re-converges on the motions since the windows began
  // to disagree, without the refinement and the pose history of the old mounting.
  void FollowShortWindow(const RigEstimatorOptions& o, const std::optional<Similarity>& nominal,
                         const internal::MotionModelChoice& choice) {
    internal::RestartFromMotionsSince(o, decalibration.disagree_since_ns, &stats);
    refined.reset();
    RestartHistory();
    convergence.stable = 0;
    ++online.decalibration_events;
    linear = internal::SolveStatistics(stats.long_stats, o, nominal, online.segment, choice,
                                       &general_model);
  }

  // The estimate to publish as `name`: the background refinement when it agrees with the
  // linear solution (flag kFlagRefined), else the linear solution; its σ inflated by
  // `inflation` unless they are the batch calibrator's on the history (time-block σ already).
  SlaveCalibration Published(const RigEstimatorOptions& o,
                             const internal::SigmaInflation& inflation, const std::string& name) {
    SlaveCalibration published = linear;
    if (refined && linear.solved() &&
        internal::RefinementAgrees(o, *refined, linear, inflation.rotation)) {
      published = *refined;
      published.motions = linear.motions;
      online.flags |= kFlagRefined;
    }
    published.name = name;
    published.motions.used = counts.used;
    const bool from_history = (online.flags & kFlagRefined) != 0 && refined_from_history;
    if (!from_history) internal::InflateSigmas(inflation, &published);
    return published;
  }

  // The median length of the master's motions in the window (0 when empty): a length in the
  // master's own unit, for the position's convergence where the cameras sit close together.
  double MasterMotionLength() const {
    if (stats.window.empty()) return 0.0;
    std::vector<double> lengths;
    lengths.reserve(stats.window.size());
    for (const internal::WindowEntry& e : stats.window) lengths.push_back(e.data.C0.norm());
    const auto middle = lengths.begin() + static_cast<std::ptrdiff_t>(lengths.size() / 2);
    std::nth_element(lengths.begin(), middle, lengths.end());
    return *middle;
  }

  // Why a usable `published` is not supported by the window's motions (batch_acceptance.h) or
  // not determined, else nullopt. The window's tests run again after kAcceptanceEvery updates,
  // in a new `generation` or when the estimate becomes usable; whether the published
  // parameters are determined is cheap and tested on every update.
  std::optional<std::string> Unsupported(const SlaveCalibration& published, uint64_t generation) {
    if (!IsUsable(published.state)) {
      acceptance_age = -1;
      return std::nullopt;
    }
    if (acceptance_age < 0 || acceptance_age >= kAcceptanceEvery ||
        acceptance_generation != static_cast<int64_t>(generation)) {
      std::vector<internal::MotionData> window;
      window.reserve(stats.window.size());
      for (const internal::WindowEntry& e : stats.window) window.push_back(e.data);
      unsupported = internal::OnlineUnsupportedReason(window, published);
      acceptance_age = 0;
      acceptance_generation = static_cast<int64_t>(generation);
    }
    ++acceptance_age;
    return unsupported ? unsupported : internal::UndeterminedReason(published);
  }
};

}  // namespace rigcal
