// SPDX-License-Identifier: Apache-2.0
// Accumulation and forgetting of the recursive estimator's statistics
// (statistics_accumulation.h).
#include "online/statistics_accumulation.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <iterator>

#include "models/linear_solvers.h"

namespace rigcal::internal {
namespace {

// The forgetting factor of dt_ns at a half-life of half_life_s seconds (1: no forgetting).
double Forget(int64_t dt_ns, double half_life_s) {
  if (half_life_s <= 0.0 || dt_ns <= 0) return 1.0;
  return std::pow(0.5, static_cast<double>(dt_ns) * 1e-9 / half_life_s);
}

// Moves a window entry into `outside`, with the weight it has in long_stats now (its weight
// when added, forgotten since).
void MoveOutside(const WindowEntry& e, SlaveStatistics* s) {
  s->outside.Add(e.data, e.data.segment, e.weight * std::exp(s->log_decay - e.log_decay));
}

void EvictOldest(SlaveStatistics* s) {
  MoveOutside(s->window.front(), s);
  s->window.pop_front();
}

void EvictSegment(int segment, SlaveStatistics* s) {
  for (auto it = s->window.begin(); it != s->window.end();) {
    if (it->data.segment != segment) {
      ++it;
      continue;
    }
    MoveOutside(*it, s);
    it = s->window.erase(it);
  }
}

}  // namespace

SlaveStatistics::SlaveStatistics(const RigEstimatorOptions& o)
    : rotation_blocks(std::max<int64_t>(1, std::llround(o.sigma_block_s * 1e9)), o.sigma_blocks) {}

void AccumulateMotion(const RigEstimatorOptions& o, const RigMotion& m, const MotionData& md,
                      double weight, const Eigen::Quaterniond& at, SlaveStatistics* s) {
  if (s->last_decay_ns >= 0) {
    const int64_t dt = m.t_b_ns - s->last_decay_ns;
    const double f = Forget(dt, o.half_life_s);
    s->long_stats.Decay(f);
    s->rotation_blocks.Decay(f);
    s->outside.Decay(f);
    s->log_decay += std::log(f);
    s->short_stats.Decay(Forget(dt, o.short_half_life_s));
  }
  s->last_decay_ns = m.t_b_ns;
  s->long_stats.Add(md, md.segment, weight);
  if (o.sigma_block_s > 0.0) {
    const Eigen::Matrix4d a = RotationConstraintMatrix(md);
    s->rotation_blocks.Add(m.t_b_ns, weight * a.transpose() * a, weight);  // (4.10) per block
  }
  s->short_stats.Add(md, md.segment, weight);
  for (MotionStatistics* stats : {&s->long_stats, &s->short_stats}) {
    while (static_cast<int>(stats->segments().size()) > o.max_open_segments) {
      int oldest = stats->segments().begin()->first;
      if (oldest == md.segment) oldest = std::next(stats->segments().begin())->first;
      const PlanarFrame frame = stats->SolvePlanarFrame();
      if (stats == &s->long_stats) {
        // The window keeps open segments only: the closed one's motions join the prior.
        EvictSegment(oldest, s);
        s->outside.MarginaliseSegment(oldest, at, frame);
      }
      stats->MarginaliseSegment(oldest, at, frame);
    }
  }
  s->window.push_back({m, weight, md, s->log_decay});
  if (static_cast<int>(s->window.size()) > o.window_size) EvictOldest(s);
}

void RestartPositions(SlaveStatistics* s) {
  s->long_stats.ResetPosition();
  s->short_stats.ResetPosition();
  s->window.clear();
  s->outside = s->long_stats;
}

void RestartFromMotionsSince(const RigEstimatorOptions& o, int64_t since_ns, SlaveStatistics* s) {
  std::deque<WindowEntry> kept;
  for (const WindowEntry& e : s->window) {
    if (e.motion.t_a_ns >= since_ns) kept.push_back(e);
  }
  s->long_stats = MotionStatistics{};
  s->short_stats = MotionStatistics{};
  s->outside = MotionStatistics{};
  s->rotation_blocks.Clear();
  for (const WindowEntry& e : kept) {
    // As much of each as the statistics held (forgetting since it was added).
    const double w = e.weight * std::exp(s->log_decay - e.log_decay);
    s->long_stats.Add(e.data, e.data.segment, w);
    s->short_stats.Add(e.data, e.data.segment, w);
    if (o.sigma_block_s > 0.0) {
      const Eigen::Matrix4d a = RotationConstraintMatrix(e.data);
      s->rotation_blocks.Add(e.motion.t_b_ns, w * a.transpose() * a, w);
    }
  }
  s->window = std::move(kept);
}

void CopyWindow(const SlaveStatistics& s, RefinementJob* job) {
  for (const auto& w : s.window) {
    job->motions.push_back(w.motion);
    job->weights.push_back(std::exp(s.log_decay - w.log_decay));
  }
  job->prior = s.outside.Quadratic();
}

}  // namespace rigcal::internal
