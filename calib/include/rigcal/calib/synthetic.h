// SPDX-License-Identifier: Apache-2.0
#pragma once
// The pose-level synthetic data generator shared by tests, experiments, benchmarks and the demo:
// rigs, master trajectories, drives with odometry-like errors (thesis samples of chapter 5 and
// smooth drives). The car rig and car-like trajectories are in synthetic_car.h; images of a
// simulated rig are rendered by drivers' SimulatedRig.

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal {

// Thesis 5.1.2 generator: dC uniform in [-10, 10]^3, dR about a uniform axis by an angle
// uniform in [-pi, pi], scale uniform in [0.01, 1].
Similarity RandomRigParameters(std::mt19937_64& rng);

// Slave pose from master pose and rig parameters, eq. (5.1) and (5.2).
Pose SlavePoseFromMaster(const Pose& master, const Similarity& rig);

// Thesis 5.1.2 perturbation: rotate R by eps about a uniform random axis and rotate the
// direction of C by eps about another uniform axis (lengths unchanged).
Pose PerturbPose(const Pose& pose, double eps_rad, std::mt19937_64& rng);

// Uniform random rotation axis.
Eigen::Vector3d RandomUnitVector(std::mt19937_64& rng);

// A vector of three draws of `distribution`, drawn z first, then y, then x. Every random vector
// of the generators and tests is drawn through this: the order in which the arguments of
// Vector3d(d(rng), d(rng), d(rng)) are evaluated is unspecified (GCC draws z first, clang x), so
// such a vector differs between compilers for the same seed. This order keeps the samples every
// seed gave with GCC (the tests' data and the thesis figures).
template <typename Distribution, typename Rng>
Eigen::Vector3d RandomVector3(Distribution& distribution, Rng& rng) {
  const double z = distribution(rng);
  const double y = distribution(rng);
  const double x = distribution(rng);
  return Eigen::Vector3d(x, y, z);
}

struct ThesisSampleOptions {
  int num_poses = 4;              // K
  int num_slaves = 1;             // N
  double eps_deg = 0.0;           // orientation error level
  double max_rotation_deg = 180;  // master rotation angle of pose k: uniform in [0, max]
  // When > 0, pose k rotates by (k/K) * fixed_rotation_deg instead (thesis 5.2).
  double fixed_rotation_deg = 0.0;
  // Slave position of pose k scaled by 1 + (k/K) * max_scale_error (thesis 5.3).
  double max_scale_error = 0.0;
  double translation_extent = 10.0;  // master positions uniform in [-e, e]^3
};

// One thesis sample: K random master poses since start (pose 0 is the identity), slaves
// from random rig parameters, all poses perturbed. `truth` gets one entry per slave.
RigRecording ThesisSample(const ThesisSampleOptions& options, std::mt19937_64& rng,
                          std::vector<Similarity>* truth);

// A smooth rig drive for demos and tests: the master follows a closed, rotating trajectory
// (sum of sinusoids in position and orientation, general 6-DoF), each slave sees it through
// its rig parameters, and every camera's poses get odometry-like errors.
struct DriveOptions {
  enum class Motion {
    kGeneral,          // 6-DoF: every axis rotates and moves
    kPlanarYaw,        // a car: yaw about the master camera's y axis, moves in its x-z plane
    kTranslationOnly,  // no rotation at all
    kStraight,         // no rotation, forward along z at translation_amplitude / 2 units per
                       // second, speeding up and slowing down: every translation parallel
  };
  Motion motion = Motion::kGeneral;
  int num_frames = 1200;
  double frame_rate_hz = 20.0;
  double rotation_amplitude_deg = 35.0;
  double translation_amplitude = 2.0;  // master units
  // The trajectory repeats every period_s seconds (0: the whole drive is one period, so a
  // longer drive moves more slowly). A drive of many periods drives the same loop again.
  double period_s = 0.0;
  double rotation_noise_deg = 0.05;  // white noise per pose
  double position_noise = 0.002;     // white noise per pose, master units
  double drift_deg_per_frame = 0.0;  // random-walk rotation drift
  uint64_t seed = 1;
  // From frame change_frame on, the slaves sit at changed_rigs (a bumped camera); the odometry
  // of every camera continues undisturbed. -1 = never.
  int change_frame = -1;
  std::vector<Similarity> changed_rigs = {};
  // Every slave's odometry re-initialises every segment_period_s seconds (0 = never): a new
  // segment id and an odometry unit multiplied by a random factor in [0.5, 2].
  double segment_period_s = 0.0;
};

// A master trajectory: world_from_master at stamp t_ns[k] (any world frame).
struct SampledTrajectory {
  std::vector<int64_t> t_ns;
  std::vector<Pose> poses;
};

struct SyntheticDrive {
  RigRecording recording;
  std::vector<Similarity> truth;  // per slave
};

// Builds a drive for the given rig (names[0] is the master, rigs[i] for names[i+1]).
SyntheticDrive GenerateDrive(const std::vector<std::string>& names,
                             const std::vector<Similarity>& rigs, const DriveOptions& options);

// The same along a given master trajectory: `world_from_master[k]` is the master's pose at stamp
// t_ns[k] (any world frame; the poses are made camera-local, pose 0 the identity). Uses the
// noise, drift, seed, change_frame/changed_rigs and segment_period_s of `options`; its motion,
// num_frames, frame_rate_hz and amplitudes are ignored.
SyntheticDrive GenerateDriveAlong(const std::vector<std::string>& names,
                                  const std::vector<Similarity>& rigs,
                                  const std::vector<int64_t>& t_ns,
                                  std::vector<Pose> world_from_master, const DriveOptions& options);
// The same along `master` (master.t_ns, master.poses).
SyntheticDrive GenerateDriveAlong(const std::vector<std::string>& names,
                                  const std::vector<Similarity>& rigs,
                                  const SampledTrajectory& master, const DriveOptions& options);

// The default 3-camera rig of the demo: master looking forward, one slave looking left and
// one looking backwards, with different odometry scales.
std::vector<Similarity> DemoRig();

}  // namespace rigcal
