// SPDX-License-Identifier: Apache-2.0
#pragma once
// Histograms of residua for the report: counts over uniform bins from 0, and the σ.

#include <vector>

namespace rigcal::report::internal {

struct Histogram {
  std::vector<double> edges;  // bins [edges[b], edges[b + 1]); the last one closed
  std::vector<int> counts;    // one per bin; they sum to `values`
  int values = 0;             // finite values counted
  double rms = 0.0;           // σ of the residua about 0: sqrt(mean of the squares)
  double median = 0.0;
};

// The histogram of the finite, non-negative `values` (magnitudes; negative ones are counted by
// their magnitude): about sqrt(n) bins (5 to 25) of a round width (1, 2 or 5 times a power of
// ten) from 0 past the largest value.
Histogram HistogramOf(const std::vector<double>& values);

}  // namespace rigcal::report::internal
