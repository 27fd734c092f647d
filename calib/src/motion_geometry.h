#pragma once
// The robust statistics of motion sets under their old names, for the estimator files that still
// use them: they live in rigcal/calib/robust_statistics.h (MedianAndSigma). Remove this header
// once no file includes it.

#include "rigcal/calib/robust_statistics.h"

namespace rigcal::internal {

using rigcal::RobustStats;
// Median and 1.4826 MAD of `values` (rigcal::MedianAndSigma).
inline constexpr auto& Robust = rigcal::MedianAndSigma;

}  // namespace rigcal::internal
