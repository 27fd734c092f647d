// SPDX-License-Identifier: Apache-2.0
#include "noise/time_blocks.h"

#include <algorithm>
#include <map>

#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {

std::vector<int> TimeBlocks(const std::vector<MotionData>& motions, int blocks) {
  std::map<int, std::vector<size_t>> by_scale;
  for (size_t k = 0; k < motions.size(); ++k) by_scale[motions[k].scale_index].push_back(k);
  std::vector<int> block(motions.size(), 0);
  for (auto& [index, members] : by_scale) {
    std::stable_sort(members.begin(), members.end(),
                     [&](size_t a, size_t b) { return motions[a].t_ns < motions[b].t_ns; });
    const size_t n = members.size();
    for (size_t rank = 0; rank < n; ++rank) {
      block[members[rank]] = static_cast<int>(rank * static_cast<size_t>(std::max(blocks, 1)) / n);
    }
  }
  return block;
}

int BlocksForDurations(const std::vector<MotionData>& motions, int max_blocks) {
  if (motions.empty() || max_blocks <= 4) return max_blocks;
  int64_t first = motions.front().t_ns, last = first;
  std::vector<double> durations;
  durations.reserve(motions.size());
  for (const auto& m : motions) {
    first = std::min(first, m.t_ns);
    last = std::max(last, m.t_ns);
    durations.push_back(static_cast<double>(m.duration_ns));
  }
  const double median = Median(durations);
  if (!(median > 0.0)) return max_blocks;
  const double fit = static_cast<double>(last - first) / (3.0 * median);
  return static_cast<int>(std::clamp(std::floor(fit), 4.0, static_cast<double>(max_blocks)));
}

}  // namespace rigcal::internal
