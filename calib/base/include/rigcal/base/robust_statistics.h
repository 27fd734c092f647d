// SPDX-License-Identifier: Apache-2.0
#pragma once
// Robust statistics shared by every layer: medians, the MAD-based robust standard deviation, RMS.
// Each function takes its values by value (it reorders a copy) and sums in the order given, so a
// caller that replaces a hand-written loop by one of these gets bit-identical results.

#include <algorithm>
#include <cstddef>
#include <vector>

namespace rigcal {

// The element of rank floor(p n) (clamped to n - 1) of the n values, p in [0, 1]: p = 0.5 gives
// the median of an odd count and the upper of the two middle values of an even count, p = 1 the
// maximum. T{} (0) for no values. O(n).
template <typename T>
T Quantile(std::vector<T> values, double p) {
  if (values.empty()) return T{};
  const size_t k =
      std::min(values.size() - 1, static_cast<size_t>(p * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

// Element n / 2 of the sorted values: the median of an odd count, the upper of the two middle
// values of an even count (no averaging: the result is one of the values, also for integers).
// T{} (0) for no values. O(n).
template <typename T>
T UpperMedian(std::vector<T> values) {
  if (values.empty()) return T{};
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
}

// The median: the middle value of an odd count, the mean of the two middle values of an even
// count. 0 for no values. O(n).
double Median(std::vector<double> values);

// Median and robust standard deviation of a sample: sigma = 1.4826 MAD (median absolute
// deviation from the median, both by Median()), which equals the standard deviation for
// normally distributed values and ignores outliers. Zeros for no values.
struct RobustStats {
  double median = 0.0;
  double sigma = 0.0;  // 1.4826 * median absolute deviation
};
RobustStats MedianAndSigma(std::vector<double> values);

// Root mean square sqrt(sum x^2 / n), summed in the given order. 0 for no values.
double Rms(const std::vector<double>& values);

}  // namespace rigcal
