// SPDX-License-Identifier: Apache-2.0
// The non-finite values the estimators' internals use for "unknown" and "unbounded".
#pragma once

#include <limits>

namespace rigcal::internal {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace rigcal::internal
