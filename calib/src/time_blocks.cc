#include "time_blocks.h"

#include <algorithm>
#include <map>

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

}  // namespace rigcal::internal
