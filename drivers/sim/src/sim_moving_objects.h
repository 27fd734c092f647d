// SPDX-License-Identifier: Apache-2.0
#pragma once
// Paths of the simulated rig's moving objects (spec.scene.moving_objects): each object slides
// back and forth along its own straight line across the free floor at a constant speed, from a
// phase of its own. Their shapes and textures are the scene's (Scene::MovingBoxCount); this
// says where they are when. Private to rigcal_sim.

#include <Eigen/Core>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/sim/simulated_rig_spec.h"

namespace rigcal::sim::internal {

// A camera centre at a stream time (world, m; seconds), for keeping the objects clear of it.
struct TimedPoint {
  double t_s = 0.0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
};

class MovingObjects {
 public:
  // No objects.
  MovingObjects() = default;
  // Lays out spec.scene.moving_objects.count lines from spec.seed on the free floor (the inner
  // 70 % of a room / yard / street's floor plan, where no static box stands). Each line is drawn
  // again (up to 100 times) until its object stays `clearance` m (plus the distance it moves in
  // `step_s`) away from every point of `cameras`, taken `step_s` apart; an error names the
  // object that cannot keep clear.
  static Expected<MovingObjects> Build(const SimulatedRigSpec& spec,
                                       const std::vector<TimedPoint>& cameras, double step_s,
                                       double clearance);

  int size() const { return static_cast<int>(paths_.size()); }
  bool empty() const { return paths_.empty(); }
  // Half the extent of every object along x, y, z (m).
  const Eigen::Vector3d& half_size() const { return half_size_; }
  // Centre of object i at stream time t_s (world, m); any t_s (the motion is periodic).
  Eigen::Vector3d CentreAt(int i, double t_s) const;
  // Every object's centre at t_s into `centres` (3 floats per object, object order).
  void CentresAt(double t_s, float* centres) const;

 private:
  struct Path {
    Eigen::Vector3d from;  // centre at one end of the line (world, m)
    Eigen::Vector3d to;    // centre at the other end
    double length_m = 1.0;
    double phase_m = 0.0;  // distance travelled at time 0, [0, 2 length)
  };
  // Whether the object on `path` keeps clear of every camera point.
  bool KeepsClear(const Path& path, const std::vector<TimedPoint>& cameras, double margin_m) const;
  Eigen::Vector3d CentreOn(const Path& path, double t_s) const;

  std::vector<Path> paths_;
  Eigen::Vector3d half_size_ = Eigen::Vector3d::Zero();
  double speed_mps_ = 0.0;
};

}  // namespace rigcal::sim::internal
