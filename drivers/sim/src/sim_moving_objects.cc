// SPDX-License-Identifier: Apache-2.0
// Paths of the simulated rig's moving objects: lines across the free floor, drawn from the seed
// until they keep clear of the cameras.
#include "sim_moving_objects.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sim_random.h"

namespace rigcal::sim::internal {
namespace {

constexpr int kMaxDraws = 100;

}  // namespace

Expected<MovingObjects> MovingObjects::Build(const SimulatedRigSpec& spec,
                                             const std::vector<TimedPoint>& cameras, double step_s,
                                             double clearance) {
  const SimulatedRigSpec::Scene::MovingObjects& m = spec.scene.moving_objects;
  MovingObjects objects;
  if (m.count <= 0) return objects;
  objects.half_size_ = 0.5 * m.size_m;
  objects.speed_mps_ = m.speed_mps;
  // Centres stay where the whole object is on the free floor (the inner 70 % of each half
  // extent); an object wider than that moves along the room's middle.
  const Eigen::Vector3d size = spec.SceneSize();
  Eigen::Vector2d reach;
  for (int a = 0; a < 2; ++a) {
    reach[a] = std::max(0.0, 0.7 * 0.5 * size[a] - objects.half_size_[a]);
  }
  const double margin_m = clearance + m.speed_mps * step_s;
  Rng rng(HashKey(spec.seed, kPurposeMovingPath));
  for (int i = 0; i < m.count; ++i) {
    bool clear = false;
    Path path;
    for (int draw = 0; draw < kMaxDraws && !clear; ++draw) {
      for (int a = 0; a < 2; ++a) {
        path.from[a] = rng.Uniform(-reach[a], reach[a]);
        path.to[a] = rng.Uniform(-reach[a], reach[a]);
      }
      path.from.z() = path.to.z() = objects.half_size_.z();
      path.length_m = std::max((path.to - path.from).norm(), 1e-3);
      path.phase_m = rng.Uniform(0.0, 2.0 * path.length_m);
      clear = objects.KeepsClear(path, cameras, margin_m);
    }
    if (!clear) {
      std::ostringstream e;
      e << "scene.moving_objects: object " << i << " (" << m.size_m.x() << " x " << m.size_m.y()
        << " x " << m.size_m.z() << " m) found no line across the floor in " << kMaxDraws
        << " draws that keeps " << clearance
        << " m clear of every camera; use fewer, smaller or lower objects";
      return Error{e.str()};
    }
    objects.paths_.push_back(path);
  }
  return objects;
}

bool MovingObjects::KeepsClear(const Path& path, const std::vector<TimedPoint>& cameras,
                               double margin_m) const {
  const Eigen::Vector3d reach = half_size_.array() + margin_m;
  for (const TimedPoint& camera : cameras) {
    const Eigen::Vector3d offset = (camera.p - CentreOn(path, camera.t_s)).cwiseAbs();
    if ((offset.array() < reach.array()).all()) return false;
  }
  return true;
}

Eigen::Vector3d MovingObjects::CentreOn(const Path& path, double t_s) const {
  const double period_m = 2.0 * path.length_m;
  double s = path.phase_m + speed_mps_ * t_s;
  s -= period_m * std::floor(s / period_m);  // [0, 2 length)
  const double along = s < path.length_m ? s : period_m - s;
  return path.from + (path.to - path.from) * (along / path.length_m);
}

Eigen::Vector3d MovingObjects::CentreAt(int i, double t_s) const {
  return CentreOn(paths_[static_cast<size_t>(i)], t_s);
}

void MovingObjects::CentresAt(double t_s, float* centres) const {
  for (size_t i = 0; i < paths_.size(); ++i) {
    const Eigen::Vector3d c = CentreOn(paths_[i], t_s);
    for (int a = 0; a < 3; ++a) centres[3 * i + a] = static_cast<float>(c[a]);
  }
}

}  // namespace rigcal::sim::internal
