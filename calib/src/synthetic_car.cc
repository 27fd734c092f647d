// SPDX-License-Identifier: Apache-2.0
// The synthetic car rig and its car-like trajectories (synthetic_car.h).
#include "rigcal/calib/synthetic_car.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "rigcal/base/quaternion.h"

namespace rigcal {
namespace {

constexpr double kPi = std::numbers::pi;

Similarity Mount(double yaw_deg, double pitch_deg, double roll_deg, const Eigen::Vector3d& c,
                 double scale) {
  // Yaw about the master's y (down), then pitch about the camera's x (negative: looks down),
  // then roll about its z.
  Similarity s;
  s.q = AxisAngle(Eigen::Vector3d::UnitY(), yaw_deg * kRadPerDeg) *
        AxisAngle(Eigen::Vector3d::UnitX(), pitch_deg * kRadPerDeg) *
        AxisAngle(Eigen::Vector3d::UnitZ(), roll_deg * kRadPerDeg);
  s.C = c;
  s.scale = scale;
  return s;
}

}  // namespace

std::vector<Similarity> CarRig() {
  return {Mount(-90.0, -12.0, 1.5, {-0.9, 0.3, -1.5}, 0.5),
          Mount(90.0, -10.0, -1.0, {0.9, 0.3, -1.5}, 2.0),
          Mount(180.0, -15.0, 0.5, {0.05, 0.4, -3.8}, 1.3)};
}

std::vector<std::string> CarRigNames() { return {"front", "left", "right", "rear"}; }

SampledTrajectory CarPath(const CarPathOptions& o) {
  SampledTrajectory out;
  const int n = static_cast<int>(std::llround(o.duration_s * o.rate_hz));
  const double dt = 1.0 / o.rate_hz;
  const double ramp_end = o.ramp_at_s + 2.0 * o.ramp_transition_s + o.ramp_length_s;
  double yaw = 0.0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    const bool on_ramp = o.ramp_at_s >= 0.0 && t >= o.ramp_at_s && t < ramp_end;
    double pitch = 0.0;  // positive: the nose up (camera z towards -y)
    if (on_ramp) {
      const double into = t - o.ramp_at_s;
      const double up = std::min(1.0, into / o.ramp_transition_s);
      const double down = std::min(1.0, std::max(0.0, (ramp_end - t) / o.ramp_transition_s));
      // Smooth (cosine) transitions between level and the slope.
      pitch = o.ramp_slope_deg * kRadPerDeg * 0.5 * (1.0 - std::cos(kPi * std::min(up, down)));
    }
    Pose p;
    p.q = AxisAngle(Eigen::Vector3d::UnitY(), yaw) * AxisAngle(Eigen::Vector3d::UnitX(), pitch);
    p.C = c;
    out.t_ns.push_back(static_cast<int64_t>(std::llround(t * 1e9)));
    out.poses.push_back(p);
    // Turns: incommensurate sinusoids (up to ~25 deg/s) around a steady 5 deg/s, so the
    // heading keeps changing (loops of ~90 m radius); none on the ramp.
    const double yaw_rate = on_ramp ? 0.0
                                    : (5.0 + 12.0 * std::sin(2.0 * kPi * t / 23.0) +
                                       8.0 * std::sin(2.0 * kPi * t / 9.1 + 1.0)) *
                                          kRadPerDeg;
    yaw += yaw_rate * dt;
    c += o.speed_mps * dt * (p.q * Eigen::Vector3d::UnitZ());
  }
  return out;
}

SampledTrajectory FlattenToYaw(const SampledTrajectory& trajectory) {
  SampledTrajectory out = trajectory;
  for (Pose& p : out.poses) {
    const Eigen::Vector3d forward = p.q * Eigen::Vector3d::UnitZ();
    p.q = AxisAngle(Eigen::Vector3d::UnitY(), std::atan2(forward.x(), forward.z()));
    p.C.y() = 0.0;
  }
  return out;
}

SyntheticDrive DriveCarRig(const SampledTrajectory& path, const DriveOptions& options) {
  return GenerateDriveAlong(CarRigNames(), CarRig(), path, options);
}

}  // namespace rigcal
