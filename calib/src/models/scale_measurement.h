// SPDX-License-Identifier: Apache-2.0
#pragma once
// Direct scale measurements from single motions (thesis 4.3.3 and 4.5).

#include <vector>

#include "motions/motion_data.h"

namespace rigcal::internal {

struct ScaleMeasurement {
  double value = 0.0;
  int motion = 0;  // index into the motion list
};

// General motion, eq. (4.18): λ^k = (C_0^T r_0) / (C_i^T r_i), rejected when
// |C_i^T r_i| <= 3 eps (4.23). Purely translational, eq. (4.31): λ^k = |C_0| / |C_i|.
std::vector<ScaleMeasurement> MeasureScales(const std::vector<MotionData>& motions, double epsilon,
                                            bool translational);

struct ScaleSummary {
  double mean = 0.0;
  double std = 0.0;           // sample standard deviation
  double sigma_thesis = 0.0;  // sqrt(sum (mean - λ^k)^2), the prior's σ in (4.27)
  double median = 0.0;
  int count = 0;
};

// Summary of the measurements whose motion uses scale variable `scale_index`.
ScaleSummary SummarizeScales(const std::vector<ScaleMeasurement>& measurements,
                             const std::vector<MotionData>& motions, int scale_index);

}  // namespace rigcal::internal
