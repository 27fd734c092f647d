#include "support/car_rig.h"

#include <cmath>
#include <filesystem>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/quaternion.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::support {
namespace {

constexpr double kPi = 3.14159265358979323846;

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

Trajectory CarPath(const CarPathOptions& o) {
  Trajectory out;
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

Expected<Trajectory> LoadKitti00() {
  const std::filesystem::path dir = std::filesystem::path(RIGCAL_SHARED_DATA_DIR) / "trajectories";
  const std::filesystem::path poses = dir / "KITTI_00_gt.txt";
  const std::filesystem::path times = dir / "KITTI_00_gt_times.txt";
  if (!std::filesystem::exists(poses) || !std::filesystem::exists(times)) {
    return Error{"KITTI 00 ground truth not found in " + dir.string()};
  }
  auto read = tools::ReadKittiTrajectory(poses.string(), times.string());
  if (!read) return Error{read.error()};
  Trajectory out;
  out.t_ns = read->t_ns;
  out.poses = read->poses;
  return out;
}

Trajectory FlattenToYaw(const Trajectory& trajectory) {
  Trajectory out = trajectory;
  for (Pose& p : out.poses) {
    const Eigen::Vector3d forward = p.q * Eigen::Vector3d::UnitZ();
    p.q = AxisAngle(Eigen::Vector3d::UnitY(), std::atan2(forward.x(), forward.z()));
    p.C.y() = 0.0;
  }
  return out;
}

SyntheticDrive DriveCarRig(const Trajectory& trajectory, double rotation_noise_deg,
                           double position_noise, uint64_t seed) {
  DriveOptions d;
  d.rotation_noise_deg = rotation_noise_deg;
  d.position_noise = position_noise;
  d.seed = seed;
  return GenerateDriveAlong(CarRigNames(), CarRig(), trajectory.t_ns, trajectory.poses, d);
}

PlanarErrors ErrorsAlongAxis(const Similarity& estimate, const Similarity& truth,
                             const Eigen::Vector3d& axis) {
  PlanarErrors e;
  const CalibrationError c = CompareToTruth(estimate, truth);
  e.rot_deg = c.rot_deg;
  e.scale_pct = c.scale_pct;
  const Eigen::Vector3d a = axis.normalized();
  const Eigen::Vector3d d = estimate.C - truth.C;
  e.axis = std::abs(d.dot(a));
  e.plane = (d - d.dot(a) * a).norm();
  return e;
}

}  // namespace rigcal::support
