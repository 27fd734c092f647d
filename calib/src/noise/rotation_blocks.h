// SPDX-License-Identifier: Apache-2.0
#pragma once
// The rotation information (4.10) of a slave's motions split into contiguous time blocks, for
// a cluster-robust σ of the online rotation: motions close in time share their errors
// (overlapping keyframe pairs, odometry drift), which the σ of independent motions misses.
// Bounded: at most `max_blocks` blocks of `block_ns` each; when full, neighbours merge
// pairwise and the block length doubles.

#include <Eigen/Core>
#include <cstdint>
#include <deque>
#include <vector>

#include "rigcal/calib/estimator_state.h"

namespace rigcal::internal {

class RotationBlocks {
 public:
  RotationBlocks() = default;
  RotationBlocks(int64_t block_ns, int max_blocks) : block_ns_(block_ns), max_blocks_(max_blocks) {}

  // Adds w AᵀA of a motion of weight w ending at t_ns.
  void Add(int64_t t_ns, const Eigen::Matrix4d& weighted_ata, double weight);
  // Forgetting, as the statistics the blocks split.
  void Decay(double factor);
  void Clear() { blocks_.clear(); }
  int size() const { return static_cast<int>(blocks_.size()); }
  // The blocks and their current length, to continue after a restart (estimator_state.h).
  std::vector<RotationBlockState> Save() const;
  int64_t block_ns() const { return block_ns_; }
  // Continues from saved blocks (at most max_blocks kept, the newest); block_ns <= 0 keeps the
  // current length.
  void Restore(int64_t block_ns, const std::vector<RotationBlockState>& blocks);

  // How much larger the cluster-robust rotation variance is than that of independent motions,
  // at the smallest eigenvector q of M = the sum of the blocks (4.11): the largest generalised
  // eigenvalue of the sandwich H⁻¹ (Σ_b g_b g_bᵀ) H⁻¹ · B / (B - 1) against σ² H⁻¹, with
  // g_b = Eᵀ M_b q block b's gradient in the tangent space E, H = diag of the eigen-gaps and
  // σ² the residual variance of (4.10). Directions whose gap is below 1 % of the largest are
  // left out (nearly planar motion: the planar solver determines them from translations).
  // 1 with fewer than `min_blocks` blocks; never below 1.
  double VarianceFactor(int min_blocks) const;

 private:
  struct Block {
    int64_t start_ns = 0;
    Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
    double weight = 0.0;
  };
  int64_t block_ns_ = 10'000'000'000;
  int max_blocks_ = 20;
  std::deque<Block> blocks_;
};

}  // namespace rigcal::internal
