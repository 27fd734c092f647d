// SPDX-License-Identifier: Apache-2.0
#include "noise/rotation_blocks.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

namespace rigcal::internal {

void RotationBlocks::Add(int64_t t_ns, const Eigen::Matrix4d& weighted_ata, double weight) {
  if (blocks_.empty() || t_ns - blocks_.back().start_ns >= block_ns_) {
    blocks_.push_back({t_ns, Eigen::Matrix4d::Zero(), 0.0});
    if (static_cast<int>(blocks_.size()) > max_blocks_) {
      // Full: neighbours merge pairwise and blocks last twice as long, so the blocks keep
      // covering the whole history evenly (the newest, just opened, stays alone).
      std::deque<Block> merged;
      const size_t full = blocks_.size() - 1;
      for (size_t k = 0; k + 1 < full; k += 2) {
        merged.push_back({blocks_[k].start_ns, blocks_[k].ata + blocks_[k + 1].ata,
                          blocks_[k].weight + blocks_[k + 1].weight});
      }
      if (full % 2 == 1) merged.push_back(blocks_[full - 1]);
      merged.push_back(blocks_.back());
      blocks_ = std::move(merged);
      block_ns_ *= 2;
    }
  }
  blocks_.back().ata += weighted_ata;
  blocks_.back().weight += weight;
}

std::vector<RotationBlockState> RotationBlocks::Save() const {
  std::vector<RotationBlockState> saved;
  for (const Block& b : blocks_) saved.push_back({b.start_ns, b.ata, b.weight});
  return saved;
}

void RotationBlocks::Restore(int64_t block_ns, const std::vector<RotationBlockState>& blocks) {
  if (block_ns > 0) block_ns_ = block_ns;
  blocks_.clear();
  const size_t first = blocks.size() > static_cast<size_t>(std::max(max_blocks_, 0))
                           ? blocks.size() - static_cast<size_t>(std::max(max_blocks_, 0))
                           : 0;
  for (size_t k = first; k < blocks.size(); ++k) {
    blocks_.push_back({blocks[k].start_ns, blocks[k].ata, blocks[k].weight});
  }
}

void RotationBlocks::Decay(double factor) {
  for (Block& b : blocks_) {
    b.ata *= factor;
    b.weight *= factor;
  }
}

double RotationBlocks::VarianceFactor(int min_blocks) const {
  const int n = size();
  if (n < std::max(min_blocks, 2)) return 1.0;
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  double weight = 0.0;
  for (const Block& b : blocks_) {
    m += b.ata;
    weight += b.weight;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(m);
  const Eigen::Vector4d& lambda = eig.eigenvalues();
  const Eigen::Vector4d q = eig.eigenvectors().col(0);
  // Residual variance of (4.10) per equation, as the σ of independent motions uses it.
  const double sigma2 = std::max(lambda(0), 0.0) / std::max(1.0, 4.0 * weight - 3.0);
  const double largest_gap = lambda(3) - lambda(0);
  if (!(sigma2 > 0.0) || !(largest_gap > 0.0)) return 1.0;
  std::vector<int> used;
  for (int j = 1; j < 4; ++j) {
    if (lambda(j) - lambda(0) >= 1e-2 * largest_gap) used.push_back(j);
  }
  const int k = static_cast<int>(used.size());
  // H^(-1/2) (Σ g gᵀ) H^(-1/2) / σ² on the used directions.
  Eigen::MatrixXd normalised = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd g(k);
  for (const Block& b : blocks_) {
    const Eigen::Vector4d mq = b.ata * q;
    for (int i = 0; i < k; ++i) {
      const int j = used[i];
      g(i) = eig.eigenvectors().col(j).dot(mq) / std::sqrt(lambda(j) - lambda(0));
    }
    normalised += g * g.transpose();
  }
  normalised *= n / (n - 1.0) / sigma2;
  const double factor =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(normalised).eigenvalues().maxCoeff();
  return std::isfinite(factor) ? std::max(1.0, factor) : 1.0;
}

}  // namespace rigcal::internal
