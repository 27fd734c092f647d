// SPDX-License-Identifier: Apache-2.0
#pragma once
// The q-quantile of a sample (nearest rank), for the device tests' latency figures; 0 when
// empty.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace rigcal::capture {

inline double SampleQuantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace rigcal::capture
