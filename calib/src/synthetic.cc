// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/synthetic.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "rigcal/base/quaternion.h"

namespace rigcal {
namespace {

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

Eigen::Quaterniond ExpMap(const Eigen::Vector3d& rotation_vector) {
  return AxisAngle(rotation_vector, rotation_vector.norm());
}

}  // namespace

Eigen::Vector3d RandomUnitVector(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d v;
  do {
    v = RandomVector3(n, rng);
  } while (v.norm() < 1e-9);
  return v.normalized();
}

Similarity RandomRigParameters(std::mt19937_64& rng) {
  Similarity s;
  std::uniform_real_distribution<double> position(-10, 10);
  s.C = RandomVector3(position, rng);
  const double angle =
      Uniform(rng, -std::numbers::pi, std::numbers::pi);  // before the axis (RandomVector3)
  s.q = AxisAngle(RandomUnitVector(rng), angle);
  s.scale = Uniform(rng, 0.01, 1.0);
  return s;
}

Pose SlavePoseFromMaster(const Pose& master, const Similarity& rig) {
  Pose slave;
  slave.q = (rig.q.conjugate() * master.q * rig.q).normalized();  // (5.1)
  const Eigen::Vector3d rhs = (master.R() - Eigen::Matrix3d::Identity()) * rig.C + master.C;
  slave.C = (rig.q.conjugate() * rhs) / rig.scale;  // (5.2)
  return slave;
}

Pose PerturbPose(const Pose& pose, double eps_rad, std::mt19937_64& rng) {
  Pose out = pose;
  if (eps_rad == 0.0) return out;
  out.q = (AxisAngle(RandomUnitVector(rng), eps_rad) * pose.q).normalized();
  out.C = AxisAngle(RandomUnitVector(rng), eps_rad) * pose.C;
  return out;
}

RigRecording ThesisSample(const ThesisSampleOptions& options, std::mt19937_64& rng,
                          std::vector<Similarity>* truth) {
  const int k_count = options.num_poses;
  std::vector<Similarity> rigs;
  for (int i = 0; i < options.num_slaves; ++i) rigs.push_back(RandomRigParameters(rng));

  std::vector<Pose> master(k_count + 1);
  for (int k = 1; k <= k_count; ++k) {
    const double angle = options.fixed_rotation_deg > 0.0
                             ? options.fixed_rotation_deg * kRadPerDeg * k / k_count
                             : Uniform(rng, 0.0, options.max_rotation_deg * kRadPerDeg);
    master[k].q = AxisAngle(RandomUnitVector(rng), angle);
    const double e = options.translation_extent;
    std::uniform_real_distribution<double> position(-e, e);
    master[k].C = RandomVector3(position, rng);
  }

  RigRecording rec;
  rec.master.name = "cam0";
  for (int k = 0; k <= k_count; ++k) rec.t_ns.push_back(static_cast<int64_t>(k) * 50'000'000);
  const double eps = options.eps_deg * kRadPerDeg;
  rec.master.poses.push_back(master[0]);
  for (int k = 1; k <= k_count; ++k) rec.master.poses.push_back(PerturbPose(master[k], eps, rng));
  rec.master.segment.assign(k_count + 1, 0);
  for (int i = 0; i < options.num_slaves; ++i) {
    CameraTrack track;
    track.name = "cam" + std::to_string(i + 1);
    track.poses.push_back(Pose{});
    for (int k = 1; k <= k_count; ++k) {
      Pose slave = SlavePoseFromMaster(master[k], rigs[i]);
      slave.C *= 1.0 + options.max_scale_error * k / k_count;  // thesis 5.3 scale drift
      track.poses.push_back(PerturbPose(slave, eps, rng));
    }
    track.segment.assign(k_count + 1, 0);
    rec.slaves.push_back(std::move(track));
  }
  if (truth) *truth = rigs;
  return rec;
}

SyntheticDrive GenerateDrive(const std::vector<std::string>& names,
                             const std::vector<Similarity>& rigs, const DriveOptions& options) {
  const int n = options.num_frames;
  const double amp_rot = options.rotation_amplitude_deg * kRadPerDeg;
  const double amp_pos = options.translation_amplitude;
  const double period = options.period_s > 0.0 ? options.period_s : n / options.frame_rate_hz;

  // Master trajectory: incommensurate sinusoids so every axis keeps rotating and moving.
  std::vector<Pose> truth_master(n);
  for (int k = 0; k < n; ++k) {
    const double t = 2.0 * std::numbers::pi * k / options.frame_rate_hz / period;
    Eigen::Vector3d rv(amp_rot * std::sin(3.0 * t), amp_rot * std::sin(5.0 * t + 1.0),
                       amp_rot * 0.8 * std::sin(2.0 * t + 2.0));
    Eigen::Vector3d pos(amp_pos * std::sin(2.0 * t), amp_pos * std::sin(3.0 * t + 0.5),
                        amp_pos * 0.5 * std::sin(4.0 * t + 1.5));
    if (options.motion == DriveOptions::Motion::kPlanarYaw) {
      rv = Eigen::Vector3d(0.0, 2.0 * amp_rot * std::sin(3.0 * t) + amp_rot * std::sin(7.0 * t),
                           0.0);
      pos.y() = 0.0;
    } else if (options.motion == DriveOptions::Motion::kTranslationOnly) {
      rv.setZero();
    } else if (options.motion == DriveOptions::Motion::kStraight) {
      const double seconds = k / options.frame_rate_hz;
      rv.setZero();
      pos = Eigen::Vector3d(0.0, 0.0, 0.5 * amp_pos * (seconds + 0.5 * std::sin(seconds)));
    }
    truth_master[k].q = ExpMap(rv);
    truth_master[k].C = pos;
  }
  std::vector<int64_t> t_ns;
  for (int k = 0; k < n; ++k) {
    t_ns.push_back(static_cast<int64_t>(std::llround(k * 1e9 / options.frame_rate_hz)));
  }
  return GenerateDriveAlong(names, rigs, t_ns, truth_master, options);
}

SyntheticDrive GenerateDriveAlong(const std::vector<std::string>& names,
                                  const std::vector<Similarity>& rigs,
                                  const std::vector<int64_t>& t_ns,
                                  std::vector<Pose> world_from_master,
                                  const DriveOptions& options) {
  std::vector<Pose> truth_master = std::move(world_from_master);
  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const int n = static_cast<int>(std::min(t_ns.size(), truth_master.size()));
  truth_master.resize(n);
  SyntheticDrive drive;
  drive.truth = rigs;
  if (n == 0) return drive;
  const Pose first_inverse = truth_master.front().Inverse();
  for (auto& p : truth_master) p = first_inverse * p;  // camera-local: pose 0 is identity

  auto& rec = drive.recording;
  rec.t_ns.assign(t_ns.begin(), t_ns.begin() + n);
  const double sigma_rot = options.rotation_noise_deg * kRadPerDeg;
  const double drift = options.drift_deg_per_frame * kRadPerDeg;
  // Pose of a slave in its own reference frame (its pose at frame 0, rig `at_start`) when the
  // rig is `now`: inv(dT_start) T_0 dT_now, eq. (5.1)/(5.2) when both are equal.
  auto slave_pose = [](const Pose& master, const Similarity& at_start, const Similarity& now) {
    Pose p;
    p.q = (at_start.q.conjugate() * master.q * now.q).normalized();
    p.C = (at_start.q.conjugate() * (master.q * now.C + master.C - at_start.C)) / at_start.scale;
    return p;
  };
  std::uniform_real_distribution<double> unit_factor(std::log(0.5), std::log(2.0));
  auto make_track = [&](const std::string& name, int slave) {
    CameraTrack track;
    track.name = name;
    Eigen::Quaterniond walk = Eigen::Quaterniond::Identity();
    const Similarity* rig = slave >= 0 ? &rigs[slave] : nullptr;
    const double unit = rig ? rig->scale : 1.0;  // master units per slave unit
    int segment = 0;
    double unit_change = 1.0;
    int64_t next_reset = options.segment_period_s > 0.0
                             ? static_cast<int64_t>(options.segment_period_s * 1e9)
                             : std::numeric_limits<int64_t>::max();
    for (int k = 0; k < n; ++k) {
      Pose p = truth_master[k];
      if (rig) {
        const bool changed = options.change_frame >= 0 && k >= options.change_frame &&
                             slave < static_cast<int>(options.changed_rigs.size());
        p = slave_pose(truth_master[k], *rig, changed ? options.changed_rigs[slave] : *rig);
        if (rec.t_ns[k] - rec.t_ns[0] >= next_reset) {
          ++segment;
          unit_change = std::exp(unit_factor(rng));
          next_reset += static_cast<int64_t>(options.segment_period_s * 1e9);
        }
        p.C *= unit_change;  // the segment's odometry unit is 1/unit_change of the first's
      }
      if (k > 0) {
        walk = (ExpMap(drift * RandomVector3(gauss, rng)) * walk).normalized();
        p.q = (walk * ExpMap(sigma_rot * RandomVector3(gauss, rng)) * p.q).normalized();
        p.C += options.position_noise / unit * unit_change * RandomVector3(gauss, rng);
      }
      track.poses.push_back(p);
      track.segment.push_back(segment);
    }
    return track;
  };
  rec.master = make_track(names.at(0), -1);
  for (size_t i = 0; i < rigs.size(); ++i) {
    rec.slaves.push_back(make_track(names.at(i + 1), static_cast<int>(i)));
  }
  return drive;
}

SyntheticDrive GenerateDriveAlong(const std::vector<std::string>& names,
                                  const std::vector<Similarity>& rigs,
                                  const SampledTrajectory& master, const DriveOptions& options) {
  return GenerateDriveAlong(names, rigs, master.t_ns, master.poses, options);
}

std::vector<Similarity> DemoRig() {
  Similarity left;  // looking left (rotated about the camera's vertical axis), metre-ish units
  left.q = AxisAngle(Eigen::Vector3d::UnitY(), -90.0 * kRadPerDeg) *
           AxisAngle(Eigen::Vector3d::UnitX(), 5.0 * kRadPerDeg);
  left.C = Eigen::Vector3d(-0.85, 0.05, -0.6);
  left.scale = 0.5;
  Similarity back;  // looking backwards
  back.q = AxisAngle(Eigen::Vector3d::UnitY(), 180.0 * kRadPerDeg) *
           AxisAngle(Eigen::Vector3d::UnitZ(), -3.0 * kRadPerDeg);
  back.C = Eigen::Vector3d(0.1, -0.1, -2.2);
  back.scale = 2.0;
  return {left, back};
}

}  // namespace rigcal
