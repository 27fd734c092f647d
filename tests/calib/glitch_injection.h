// SPDX-License-Identifier: Apache-2.0
#pragma once
// Glitch injection shared by the glitch tests: 1 % of the poses glitched, each in a random
// camera: a jump by 20-100 % of the trajectory's extent in a random direction, or a rotation by
// 30-180 degrees about a random axis.

#include <random>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/base/types.h"

namespace rigcal::testing {

inline CameraTrack& Track(RigRecording* rec, int camera) {
  return camera == 0 ? rec->master : rec->slaves[camera - 1];
}

// Returns the glitched times.
inline std::vector<int> GlitchOnePercent(RigRecording* rec, std::mt19937_64& rng) {
  std::vector<int> where;
  const int n = static_cast<int>(rec->size());
  const int cameras = 1 + static_cast<int>(rec->slaves.size());
  std::uniform_int_distribution<int> index(0, n - 1), camera(0, cameras - 1), kind(0, 1);
  std::uniform_real_distribution<double> fraction(0.2, 1.0), angle(30.0, 180.0);
  for (int g = 0; g < n / 100; ++g) {
    const int k = index(rng);
    CameraTrack& t = Track(rec, camera(rng));
    Eigen::Vector3d lo = t.poses[0].C, hi = lo;
    for (const Pose& p : t.poses) {
      lo = lo.cwiseMin(p.C);
      hi = hi.cwiseMax(p.C);
    }
    if (kind(rng) == 0) {
      const Eigen::Vector3d direction = RandomUnitVector(rng);  // drawn first (RandomVector3)
      t.poses[k].C += fraction(rng) * (hi - lo).norm() * direction;
    } else {
      const double angle_rad = angle(rng) * kRadPerDeg;  // drawn first (RandomVector3)
      t.poses[k].q = t.poses[k].q * AxisAngle(RandomUnitVector(rng), angle_rad);
    }
    where.push_back(k);
  }
  return where;
}

}  // namespace rigcal::testing
