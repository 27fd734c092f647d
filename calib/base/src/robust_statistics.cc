// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/robust_statistics.h"

#include <cmath>

namespace rigcal {

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  double m = values[mid];
  // Even count: the lower middle value is the largest of those before the upper one.
  if (values.size() % 2 == 0) {
    m = 0.5 *
        (m + *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid)));
  }
  return m;
}

RobustStats MedianAndSigma(std::vector<double> values) {
  RobustStats s;
  if (values.empty()) return s;
  s.median = Median(values);
  for (double& x : values) x = std::abs(x - s.median);
  s.sigma = 1.4826 * Median(std::move(values));
  return s;
}

double Rms(const std::vector<double>& values) {
  if (values.empty()) return 0.0;
  double sum_sq = 0.0;
  for (const double x : values) sum_sq += x * x;
  return std::sqrt(sum_sq / static_cast<double>(values.size()));
}

}  // namespace rigcal
