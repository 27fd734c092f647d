#include "motion_geometry.h"

#include <algorithm>
#include <cmath>

namespace rigcal::internal {

RobustStats Robust(std::vector<double> values) {
  RobustStats s;
  if (values.empty()) return s;
  auto median_of = [](std::vector<double>& v) {
    const size_t mid = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + mid, v.end());
    double m = v[mid];
    if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + mid));
    return m;
  };
  s.median = median_of(values);
  for (double& x : values) x = std::abs(x - s.median);
  s.sigma = 1.4826 * median_of(values);
  return s;
}

}  // namespace rigcal::internal
