// SPDX-License-Identifier: Apache-2.0
#pragma once
// Rig trajectories of the simulated rig: a cumulative cubic B-spline through waypoints, or a
// sampled trajectory (file) interpolated linearly with slerp. Private to rigcal_sim.

#include <cstdint>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::sim::internal {

class Trajectory {
 public:
  // C2 B-spline: control points are the waypoints plus a reflected phantom point at each end,
  // so the curve starts exactly at waypoints.front() (time 0) and ends exactly at
  // waypoints.back() (time (n - 1) * interval_s). Needs >= 2 waypoints and interval_s > 0.
  static Trajectory FromWaypoints(const std::vector<Pose>& waypoints, double interval_s);
  // Sampled world_from_body poses at strictly increasing stamps (>= 2); the first stamp is time
  // 0. The result is world_from_body * body_from_master.
  static Trajectory FromSamples(const std::vector<int64_t>& t_ns, const std::vector<Pose>& poses,
                                const Pose& body_from_master);

  // world_from_master at time t_s (seconds, clamped to [0, duration_s()]).
  Pose At(double t_s) const;
  double duration_s() const { return duration_s_; }

 private:
  bool spline_ = false;
  double duration_s_ = 0.0;
  // Spline: control points (phantoms included) and knot interval.
  std::vector<Pose> control_;
  double interval_s_ = 1.0;
  // Samples.
  std::vector<double> t_s_;
  std::vector<Pose> samples_;
  Pose body_from_master_;
};

}  // namespace rigcal::sim::internal
