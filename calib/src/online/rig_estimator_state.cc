// SPDX-License-Identifier: Apache-2.0
// RigEstimator's state across a restart: what SaveState keeps of every slave (estimator_state.h)
// and how RestoreState takes it back, publishing exactly the estimate of before the restart
// until new data arrive.
#include <memory>
#include <string>
#include <vector>

#include "online/rig_estimator_slave.h"
#include "rigcal/calib/rig_estimator.h"

namespace rigcal {

RigEstimatorState RigEstimator::SaveState() const {
  RigEstimatorState state;
  state.cameras = names_;
  state.master_segment = master_segment_;
  state.have_master_segment = have_master_segment_;
  state.consumed_t_ns = consumed_t_ns_;
  state.first_consumed = first_consumed_;
  state.last_consumed = last_consumed_;
  for (const auto& slave : slaves_) {
    const Slave& s = *slave;
    SlaveEstimatorState& saved = state.slaves.emplace_back();
    saved.counts = s.counts;
    saved.angle_var = s.gates.angle_var;
    saved.rot_var = s.gates.rot_var;
    saved.pos_var = s.gates.pos_var;
    saved.ci_sq = s.gates.ci_sq;
    saved.segment = s.online.segment;
    saved.rotating = s.rotating;
    saved.general_model = s.general_model;
    saved.long_stats = s.stats.long_stats.Sums();
    saved.short_stats = s.stats.short_stats.Sums();
    const size_t i = state.slaves.size() - 1;
    s.SavePublished(estimate_.rig.slaves[i], estimate_.online[i], &saved.resume);
  }
  return state;
}

Status RigEstimator::RestoreState(const RigEstimatorState& state) {
  if (state.cameras.size() != names_.size()) {
    return Error{"state is for a different rig (camera count)"};
  }
  for (size_t i = 0; i < names_.size(); ++i) {
    if (state.cameras[i] != names_[i]) {
      return Error{"state is for a different rig (camera '" + names_[i] + "')"};
    }
  }
  if (state.slaves.size() != slaves_.size()) {
    return Error{"state has " + std::to_string(state.slaves.size()) + " slaves for " +
                 std::to_string(slaves_.size()) + " slave cameras"};
  }
  std::vector<std::unique_ptr<Slave>> restored;
  for (const SlaveEstimatorState& saved : state.slaves) {
    // Not saved: the keyframes, the window (all of it is prior now) and the time blocks.
    auto s = std::make_unique<Slave>(options_);
    s->counts = saved.counts;
    s->gates.angle_var = saved.angle_var;
    s->gates.rot_var = saved.rot_var;
    s->gates.pos_var = saved.pos_var;
    s->gates.ci_sq = saved.ci_sq;
    s->online.segment = saved.segment;
    s->rotating = saved.rotating;
    s->general_model = saved.general_model;
    s->stats.long_stats = internal::MotionStatistics::FromSums(saved.long_stats);
    s->stats.short_stats = internal::MotionStatistics::FromSums(saved.short_stats);
    s->stats.outside = s->stats.long_stats;
    s->history_complete = false;  // the saved motions are not in any history
    s->RestoreInflation(saved.resume);
    restored.push_back(std::move(s));
  }
  slaves_ = std::move(restored);
  master_segment_ = state.master_segment;
  have_master_segment_ = state.have_master_segment;
  consumed_t_ns_.assign(names_.size(), -1);
  if (state.consumed_t_ns.size() == names_.size()) consumed_t_ns_ = state.consumed_t_ns;
  first_consumed_.assign(names_.size(), PoseFingerprint{});
  last_consumed_.assign(names_.size(), PoseFingerprint{});
  if (state.first_consumed.size() == names_.size()) first_consumed_ = state.first_consumed;
  if (state.last_consumed.size() == names_.size()) last_consumed_ = state.last_consumed;
  ++generation_;
  for (size_t i = 0; i < slaves_.size(); ++i) {
    Publish(static_cast<int>(i));
    const SlavePublishedState& r = state.slaves[i].resume;
    if (!r.present) continue;
    // Without new data the estimate is the one published before the restart, exactly: the
    // refinement it may rest on (the batch calibrator's on a pose history the state does not
    // hold) cannot be recomputed from the statistics.
    Slave& s = *slaves_[i];
    s.convergence.stable = r.stable;
    s.convergence.last_q = r.last_q;
    s.online = r.online;
    s.refined = r.refined;
    s.refined_from_history = r.refined_from_history;
    s.restored_unchanged = true;
    s.decalibration = r.decalibration;  // the alarm holds on (none from a version-6 state)
    estimate_.rig.slaves[i] = r.published;
    estimate_.online[i] = r.online;
  }
  return Status::Ok();
}

}  // namespace rigcal
