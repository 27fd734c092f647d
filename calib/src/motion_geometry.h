#pragma once
// Robust statistics of motion sets, for misfit removal.

#include <Eigen/Core>
#include <vector>

#include "motion_data.h"

namespace rigcal::internal {

struct RobustStats {
  double median = 0.0;
  double sigma = 0.0;  // 1.4826 * median absolute deviation
};
RobustStats Robust(std::vector<double> values);

}  // namespace rigcal::internal
