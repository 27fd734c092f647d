#pragma once
// Figures of the motion set that decide what it can determine: rotation-axis spread
// (planar motion) and robust statistics for misfit removal.

#include <Eigen/Core>
#include <vector>

#include "motion_data.h"

namespace rigcal::internal {

struct AxisSpread {
  double spread_deg = 0.0;  // RMS angle of the axes around their principal axis
  Eigen::Vector3d principal_axis = Eigen::Vector3d::UnitZ();
};

// Spread of the master rotation axes (sign-free: the scatter matrix sum r r^T).
AxisSpread MasterAxisSpread(const std::vector<MotionData>& motions);

struct RobustStats {
  double median = 0.0;
  double sigma = 0.0;  // 1.4826 * median absolute deviation
};
RobustStats Robust(std::vector<double> values);

}  // namespace rigcal::internal
