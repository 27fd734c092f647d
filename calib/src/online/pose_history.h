// SPDX-License-Identifier: Apache-2.0
#pragma once
// One slave's pose history (RigEstimatorOptions::history_sets): the sets since the last restart,
// on which the batch calibrator refines the published estimate. A drive longer than the history
// is kept whole at a coarser resolution: consecutive sets are merged into their group mean.

#include <cstdint>
#include <deque>

#include "rigcal/base/types.h"

namespace rigcal::internal {

// A set of the history (master and slave poses at one time), or the group mean of `sets`
// consecutive sets of one scale segment each.
struct HistorySet {
  uint64_t index = 0;  // the estimator's count of sets before the first set merged into this one
  int64_t t_ns = 0;    // the mean stamp of the sets merged
  Pose master;
  Pose slave;
  int master_segment = 0;
  int slave_segment = 0;
  int sets = 1;
};

// The weighted mean of two poses in the group of rigid motions: a · exp(w · log(a⁻¹ b)), which
// is b's share w of the way from a to b. It commutes with a rigid motion applied on either side
// and with scaling the translations, so the means of a master's and a slave's poses at the same
// times are related by the same mounting, world alignment and odometry scale as the poses.
Pose GroupMean(const Pose& a, const Pose& b, double weight_b);

class PoseHistory {
 public:
  // Adds the set with the estimator's index `set.index`. The history keeps at most `capacity`
  // entries: once the sets since the restart outnumber it, it doubles the number of sets each
  // entry merges (the stride).
  void Record(int capacity, const HistorySet& set);
  void Restart();

  const std::deque<HistorySet>& sets() const { return sets_; }
  // A power of two: each entry merges the sets whose indices share index / stride.
  uint64_t stride() const { return stride_; }

 private:
  uint64_t GroupsSinceStart(uint64_t index) const;
  void Coarsen();

  std::deque<HistorySet> sets_;
  uint64_t stride_ = 1;
  uint64_t start_index_ = 0;  // index of the first set since the restart
  bool started_ = false;
};

}  // namespace rigcal::internal
