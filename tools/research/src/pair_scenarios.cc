// SPDX-License-Identifier: Apache-2.0
// The recordings of the pair-policy evaluation and their pose noise (pair_evaluation.h).
#include <cmath>
#include <filesystem>
#include <random>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/synthetic_car.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/research/pair_evaluation.h"

namespace rigcal::research {
namespace {

Eigen::Vector3d Gauss3(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  return {g(rng), g(rng), g(rng)};
}

Eigen::Quaterniond SmallRotation(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  return angle > 0.0 ? AxisAngle(v / angle, angle) : Eigen::Quaterniond::Identity();
}

// Noise levels, lengths in units of `length` (1 for a room, 10 for a car: metres per unit).
PoseNoiseModel Mocap(double length) { return {"mocap", 0.05, 0.001 * length, 0.0, 0.0}; }
PoseNoiseModel Pnp(double length) { return {"pnp", 0.3, 0.005 * length, 0.0, 0.0}; }
PoseNoiseModel Vo(double length) { return {"vo", 0.02, 0.0005 * length, 0.02, 0.01}; }
PoseNoiseModel VoStrong(double length) { return {"vo-strong", 0.05, 0.001 * length, 0.1, 0.03}; }

SampledTrajectory Subsample(const SampledTrajectory& t, int every, double max_duration_s) {
  SampledTrajectory out;
  for (size_t k = 0; k < t.poses.size(); k += every) {
    if (max_duration_s > 0.0 &&
        1e-9 * static_cast<double>(t.t_ns[k] - t.t_ns[0]) > max_duration_s) {
      break;
    }
    out.t_ns.push_back(t.t_ns[k]);
    out.poses.push_back(t.poses[k]);
  }
  return out;
}

// The master of a simulated 6-DoF drive, without noise.
SampledTrajectory SimulatedMaster(int frames, double rate_hz, double rotation_deg) {
  DriveOptions drive;
  drive.num_frames = frames;
  drive.frame_rate_hz = rate_hz;
  drive.rotation_amplitude_deg = rotation_deg;
  drive.rotation_noise_deg = 0.0;
  drive.position_noise = 0.0;
  const SyntheticDrive d = GenerateDrive({"front", "left", "back"}, DemoRig(), drive);
  return {d.recording.t_ns, d.recording.master.poses};
}

std::optional<SampledTrajectory> Load(const std::string& path, const std::string& times,
                                      std::vector<std::string>* notes) {
  if (!std::filesystem::exists(path)) {
    notes->push_back(path + " not found: its scenarios are left out");
    return std::nullopt;
  }
  io::TrajectoryReadOptions read;
  read.max_quaternion_norm_error = 1e-3;  // printed ground truths have 6-7 digits
  auto loaded =
      times.empty() ? io::ReadTrajectory(path, read) : io::ReadKittiTrajectory(path, times);
  if (!loaded) {
    notes->push_back(loaded.error() + ": its scenarios are left out");
    return std::nullopt;
  }
  return SampledTrajectory{loaded->t_ns, loaded->poses};
}

void Add(std::vector<PairScenario>* out, const std::string& name, const std::string& source,
         const SampledTrajectory& master, bool car, const std::vector<PoseNoiseModel>& noises) {
  for (const auto& noise : noises) {
    PairScenario s;
    s.name = name + "-" + noise.name;
    s.source = source;
    s.master = master;
    s.names = car ? CarRigNames() : std::vector<std::string>{"front", "left", "back"};
    s.rig = car ? CarRig() : DemoRig();
    s.noise = noise;
    s.planar = car;
    out->push_back(std::move(s));
  }
}

// A rig laid out unlike the demo and car rigs: four cameras, one looking up, one down and
// back, one sideways on a long boom; odometry scales from a tenth to four times the master's.
std::vector<Similarity> HeldOutRig() {
  auto rot = [](const Eigen::Vector3d& axis, double deg) {
    return Eigen::Quaterniond(Eigen::AngleAxisd(deg * kRadPerDeg, axis.normalized()));
  };
  Similarity up{rot(Eigen::Vector3d::UnitX(), -80.0), Eigen::Vector3d(0.1, -0.35, 0.2), 0.1};
  Similarity down_back{rot(Eigen::Vector3d(0.2, 1.0, 0.1), 150.0), Eigen::Vector3d(-0.3, 0.4, -0.9),
                       4.0};
  Similarity boom{rot(Eigen::Vector3d::UnitY(), 75.0), Eigen::Vector3d(1.6, 0.05, 0.3), 1.3};
  return {up, down_back, boom};
}

void AddHeldOut(std::vector<PairScenario>* out, const std::string& name, const std::string& source,
                const SampledTrajectory& master, bool planar,
                const std::vector<PoseNoiseModel>& noises) {
  for (const auto& noise : noises) {
    PairScenario s;
    s.name = name + "-" + noise.name;
    s.source = source;
    s.master = master;
    s.names = {"main", "up", "downback", "boom"};
    s.rig = HeldOutRig();
    s.noise = noise;
    s.planar = planar;
    out->push_back(std::move(s));
  }
}

// White pose noise only, at the level of a good PnP and of a poor one.
PoseNoiseModel White(double length) { return {"white", 0.1, 0.002 * length, 0.0, 0.0}; }
PoseNoiseModel WhiteStrong(double length) { return {"white-strong", 0.5, 0.01 * length, 0.0, 0.0}; }
PoseNoiseModel DriftOnly() { return {"drift", 0.0, 0.0, 0.03, 0.02}; }

}  // namespace

CameraTrack AddPoseNoise(const CameraTrack& exact, const PoseNoiseModel& noise, double unit,
                         std::mt19937_64& rng) {
  CameraTrack out = exact;
  const double drift_rot = noise.drift_rot_deg * kRadPerDeg;
  const double white_rot = noise.white_rot_deg * kRadPerDeg;
  Pose drifted = exact.poses.empty() ? Pose{} : exact.poses.front();
  for (size_t k = 1; k < exact.poses.size(); ++k) {
    Pose step = exact.poses[k - 1].Between(exact.poses[k]);
    if (drift_rot > 0.0 || noise.drift_trans_fraction > 0.0) {
      step.q = (step.q * SmallRotation(drift_rot * Gauss3(rng))).normalized();
      step.C += noise.drift_trans_fraction * step.C.norm() * Gauss3(rng);
    }
    drifted = drifted * step;
    Pose p = drifted;
    p.q = (SmallRotation(white_rot * Gauss3(rng)) * p.q).normalized();
    p.C += noise.white_pos / unit * Gauss3(rng);
    out.poses[k] = p;
  }
  return out;
}

std::vector<PairScenario> PairScenarios(const std::string& trajectory_dir,
                                        std::vector<std::string>* notes) {
  std::vector<PairScenario> out;
  // Simulated 6-DoF (room-sized, metre units) and car drives.
  Add(&out, "sim-20Hz-slow", "simulated 6-DoF, 15 deg amplitude, 60 s",
      SimulatedMaster(1200, 20.0, 15.0), false, {Mocap(1), Pnp(1), Vo(1)});
  Add(&out, "sim-30Hz-fast", "simulated 6-DoF, 60 deg amplitude, 60 s",
      SimulatedMaster(1800, 30.0, 60.0), false, {Mocap(1), Vo(1), VoStrong(1)});
  Add(&out, "sim-100Hz-short", "simulated 6-DoF, 35 deg amplitude, 10 s",
      SimulatedMaster(1000, 100.0, 35.0), false, {Mocap(1), Vo(1)});
  Add(&out, "sim-10Hz-long", "simulated 6-DoF, 35 deg amplitude, 300 s",
      SimulatedMaster(3000, 10.0, 35.0), false, {Pnp(1), Vo(1)});
  CarPathOptions car;
  car.duration_s = 240.0;
  car.rate_hz = 20.0;
  Add(&out, "car-20Hz", "simulated car on a level road, 240 s", CarPath(car), true,
      {Mocap(10), Vo(10)});

  const std::string dir = trajectory_dir.empty() ? "" : trajectory_dir + "/";
  if (trajectory_dir.empty()) {
    notes->push_back("no trajectory directory given (--data): real trajectories left out");
    return out;
  }
  if (auto kitti = Load(dir + "KITTI_00_gt.txt", dir + "KITTI_00_gt_times.txt", notes)) {
    Add(&out, "kitti00-10Hz", "KITTI 00 ground truth (car, 3.7 km)", *kitti, true,
        {Mocap(10), Vo(10), VoStrong(10)});
    Add(&out, "kitti00-10Hz-short", "KITTI 00 ground truth, first 60 s", Subsample(*kitti, 1, 60.0),
        true, {Pnp(10), Vo(10)});
  }
  if (auto euroc = Load(dir + "V102_groundtruth.csv", "", notes)) {
    Add(&out, "euroc-v102-20Hz", "EuRoC V1_02 ground truth (hand-held drone, 83 s)",
        Subsample(*euroc, 10, 0.0), false, {Mocap(1), Pnp(1), Vo(1)});
    Add(&out, "euroc-v102-100Hz", "EuRoC V1_02 ground truth at 100 Hz", Subsample(*euroc, 2, 0.0),
        false, {Mocap(1), Vo(1)});
    Add(&out, "euroc-v102-10Hz-short", "EuRoC V1_02 ground truth, 10 Hz, first 30 s",
        Subsample(*euroc, 20, 30.0), false, {Pnp(1), Vo(1)});
  }
  return out;
}

std::vector<PairScenario> HeldOutPairScenarios(const std::string& trajectory_dir,
                                               std::vector<std::string>* notes) {
  std::vector<PairScenario> out;
  AddHeldOut(&out, "held-sim-5Hz-long", "simulated 6-DoF, 25 deg amplitude, 5 Hz, 600 s",
             SimulatedMaster(3000, 5.0, 25.0), false, {White(1), DriftOnly()});
  AddHeldOut(&out, "held-sim-50Hz-40s", "simulated 6-DoF, 50 deg amplitude, 50 Hz, 40 s",
             SimulatedMaster(2000, 50.0, 50.0), false, {White(1), WhiteStrong(1)});
  const std::string dir = trajectory_dir.empty() ? "" : trajectory_dir + "/";
  if (trajectory_dir.empty()) {
    notes->push_back("no trajectory directory given (--data): real trajectories left out");
    return out;
  }
  if (auto euroc = Load(dir + "V102_groundtruth.csv", "", notes)) {
    AddHeldOut(&out, "held-euroc-v102-40Hz", "EuRoC V1_02 ground truth at 40 Hz",
               Subsample(*euroc, 5, 0.0), false, {White(1), WhiteStrong(1), DriftOnly()});
  }
  if (auto kitti = Load(dir + "KITTI_00_gt.txt", dir + "KITTI_00_gt_times.txt", notes)) {
    AddHeldOut(&out, "held-kitti00-5Hz", "KITTI 00 ground truth at 5 Hz, first 200 s",
               Subsample(*kitti, 2, 200.0), true, {White(10)});
  }
  return out;
}

}  // namespace rigcal::research
