// SPDX-License-Identifier: Apache-2.0
// The master's typical travel (master_travel.h).
#include "motions/master_travel.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace rigcal::internal {

void MasterTravel::Add(int64_t t_ns, const Pose& master, int segment) {
  if (segment_ != segment) {  // a new unit: speeds in the old one mean nothing
    steps_.clear();
  } else if (t_ns > last_t_ns_) {
    const double dt_s = static_cast<double>(t_ns - last_t_ns_) * 1e-9;
    const double speed = (master.C - last_.C).norm() / dt_s;
    if (std::isfinite(speed)) steps_.push_back({t_ns, speed});
  }
  segment_ = segment;
  last_t_ns_ = t_ns;
  last_ = master;
  while (!steps_.empty() &&
         (steps_.size() > kMaxSteps || t_ns - steps_.front().t_ns > window_ns_)) {
    steps_.pop_front();
  }
}

double MasterTravel::DistanceIn(double seconds) const {
  if (steps_.empty()) return std::numeric_limits<double>::infinity();
  std::vector<double> speeds;
  speeds.reserve(steps_.size());
  for (const Step& s : steps_) speeds.push_back(s.speed_per_s);
  auto middle = speeds.begin() + static_cast<std::ptrdiff_t>(speeds.size() / 2);
  std::nth_element(speeds.begin(), middle, speeds.end());
  return seconds * *middle;
}

}  // namespace rigcal::internal
