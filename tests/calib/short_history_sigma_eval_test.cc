// SPDX-License-Identifier: Apache-2.0
// σ coverage of the batch calibrator on short pose histories (the online history refinement
// after a restart solves the sets since the restart: 100-460 of them). Many seeds of simulated
// drives at 20 Hz, the batch's σ of rotation, C and scale against its errors: the normalised
// errors z = error / σ must have an RMS of about 1 and a 99th percentile of |z| of about 2.6
// (normal), at every length and for white pose noise as well as drifting, VO-like odometry.
// Label eval (not in `make test`): `ctest -L eval -R calib/short_history_sigma --verbose`;
// RIGCAL_SIGMA_EVAL_DRAWS=N draws per cell (default 40, ~6 min on one core).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

// The pose errors of a drive: white per pose, plus the errors of monocular odometry, which
// chains its frame-to-frame motions: each increment's rotation and translation is off by a
// little, and the pose carries every earlier increment's error (drift in rotation and
// position, correlated along the drive).
struct PoseNoise {
  std::string name;
  double white_rotation_deg = 0.0;
  double white_position = 0.0;  // master units
  double step_rotation_deg = 0.0;
  double step_position = 0.0;  // master units per frame
};

Eigen::Quaterniond ExpOf(const Eigen::Vector3d& v) { return AxisAngle(v, v.norm()); }

// `track` (noise-free, camera-local, in the camera's unit `unit` master units) with `noise`.
void AddPoseNoise(const PoseNoise& noise, double unit, std::mt19937_64& rng, CameraTrack* track) {
  std::normal_distribution<double> gauss(0.0, 1.0);
  const std::vector<Pose> truth = track->poses;
  Pose odometry = truth.front();
  for (size_t k = 1; k < truth.size(); ++k) {
    Pose step = truth[k - 1].Between(truth[k]);
    step.q = (step.q * ExpOf(noise.step_rotation_deg * kRadPerDeg * RandomVector3(gauss, rng)))
                 .normalized();
    step.C += noise.step_position / unit * RandomVector3(gauss, rng);
    odometry = odometry * step;
    Pose pose = odometry;
    pose.q = (ExpOf(noise.white_rotation_deg * kRadPerDeg * RandomVector3(gauss, rng)) * pose.q)
                 .normalized();
    pose.C += noise.white_position / unit * RandomVector3(gauss, rng);
    track->poses[k] = pose;
  }
}

// A drive of `frames` sets at 20 Hz on the demo rig (two slaves), its last `length` sets.
SyntheticDrive Drive(const PoseNoise& noise, int frames, int length, uint64_t seed) {
  DriveOptions options;
  options.num_frames = frames;
  options.frame_rate_hz = 20.0;
  options.period_s = 24.0;  // the thesis scene's 468 frames
  options.rotation_noise_deg = 0.0;
  options.position_noise = 0.0;
  options.seed = seed;
  SyntheticDrive d = GenerateDrive({"m", "s1", "s2"}, DemoRig(), options);
  std::mt19937_64 rng(seed * 7919 + 17);
  AddPoseNoise(noise, 1.0, rng, &d.recording.master);
  for (size_t i = 0; i < d.recording.slaves.size(); ++i) {
    AddPoseNoise(noise, d.truth[i].scale, rng, &d.recording.slaves[i]);
  }
  RigRecording& r = d.recording;
  const size_t first = r.size() - static_cast<size_t>(length);
  r.t_ns.erase(r.t_ns.begin(), r.t_ns.begin() + first);
  for (CameraTrack* t : {&r.master, &r.slaves[0], &r.slaves[1]}) {
    t->poses.erase(t->poses.begin(), t->poses.begin() + first);
    if (!t->segment.empty()) t->segment.erase(t->segment.begin(), t->segment.begin() + first);
  }
  return d;
}

// Normalised errors of one kind of parameter.
struct Coverage {
  std::vector<double> z;
  void Add(double error, double sigma) {
    if (std::isfinite(error) && sigma > 0.0 && std::isfinite(sigma)) z.push_back(error / sigma);
  }
  double Rms() const {
    double s = 0.0;
    for (double v : z) s += v * v;
    return z.empty() ? 0.0 : std::sqrt(s / z.size());
  }
  double P99() const {
    std::vector<double> a;
    for (double v : z) a.push_back(std::abs(v));
    std::sort(a.begin(), a.end());
    return a.empty() ? 0.0 : a[static_cast<size_t>(std::ceil(0.99 * a.size())) - 1];
  }
};

struct LengthCoverage {
  Coverage rotation, position, scale;
  int solved = 0, results = 0;
};

// Rotation: the error's rotation vector per axis over the largest axis σ (what the result
// reports), C per master axis over its σ, the scale over its σ.
void AddResult(const SlaveCalibration& s, const Similarity& truth, LengthCoverage* c) {
  ++c->results;
  if (!s.solved() || !s.usable()) return;
  ++c->solved;
  const Eigen::Vector3d rot = RotationVector(Canonical(truth.q.conjugate() * s.estimate.q));
  for (int a = 0; a < 3; ++a) c->rotation.Add(rot[a] * kDegPerRad, s.rot_std_deg);
  if (s.position_observable && s.motion_model == MotionModel::kGeneral) {
    for (int a = 0; a < 3; ++a) c->position.Add(s.estimate.C[a] - truth.C[a], s.pos_std[a]);
  }
  for (const SegmentScale& sc : s.scales) c->scale.Add(sc.scale - truth.scale, sc.std);
}

int Draws() {
  const char* env = std::getenv("RIGCAL_SIGMA_EVAL_DRAWS");
  return env != nullptr ? std::max(1, std::atoi(env)) : 40;
}

LengthCoverage Evaluate(const PoseNoise& noise, int length, int draws) {
  LengthCoverage c;
  for (int seed = 1; seed <= draws; ++seed) {
    const SyntheticDrive d = Drive(noise, 460, length, static_cast<uint64_t>(seed));
    const RigCalibration r = CalibrateRig(d.recording, CalibrationOptions{});
    for (size_t i = 0; i < r.slaves.size(); ++i) AddResult(r.slaves[i], d.truth[i], &c);
  }
  return c;
}

std::vector<PoseNoise> Noises() {
  return {
      {"white", 0.05, 0.002, 0.0, 0.0},
      {"vo drift", 0.01, 0.0005, 0.02, 0.001},
      {"vo drift strong", 0.02, 0.001, 0.05, 0.003},
  };
}

// The bounds: an honest σ gives z RMS 1 (rotation: at most 1, its σ is the largest axis's) and
// a 99th percentile of |z| of 2.6; over 40 draws x 2 slaves the RMS of one cell is known to about
// ±0.15 and its p99 to about ±0.7 (the three components of a result share its σ and errors).
// The bounds are what the σ floor of batch_sigma_floor.h reaches, not that target: on drifting
// drives of 100-170 sets the RMS of C is 1.19-1.33 and of the scale 1.43-1.54, their p99 3.4-5.8
// (docs/evaluations.md, "σ on short histories"); the floor with one d per parameter alone (no
// λ of the block) gave C 1.41-1.42 and scale 1.60 at 100 sets, beyond these bounds. Without the
// floor: C RMS 3.9 and p99 11-13 at 100 sets, scale p99 29 at 100 and 8-11 at 170 and 460. The
// draws are seeded, so a change of the σ is seen on the same drives.
constexpr double kMaxRmsRotation = 1.2;
constexpr double kMaxRmsPosition = 1.36;
constexpr double kMaxRmsScale = 1.58;
constexpr double kMaxP99 = 6.0;

void ExpectCovered(const std::string& what, const Coverage& c, double max_rms,
                   const std::string& cell) {
  EXPECT_FALSE(c.z.empty()) << cell << ": no " << what;
  EXPECT_LE(c.Rms(), max_rms) << cell << ": " << what << " z RMS";
  EXPECT_LE(c.P99(), kMaxP99) << cell << ": " << what << " z p99";
}

TEST(ShortHistorySigma, CoverageAtEveryLength) {
  const int draws = Draws();
  for (const PoseNoise& noise : Noises()) {
    for (int length : {100, 170, 300, 460}) {
      const LengthCoverage c = Evaluate(noise, length, draws);
      std::printf(
          "%-16s %3d sets: %3d/%3d usable | z RMS / p99: rotation %.2f / %.2f, C %.2f / %.2f, "
          "scale %.2f / %.2f\n",
          noise.name.c_str(), length, c.solved, c.results, c.rotation.Rms(), c.rotation.P99(),
          c.position.Rms(), c.position.P99(), c.scale.Rms(), c.scale.P99());
      std::fflush(stdout);
      const std::string cell = noise.name + ", " + std::to_string(length) + " sets";
      EXPECT_GE(c.solved, c.results * 9 / 10) << cell;
      ExpectCovered("rotation", c.rotation, kMaxRmsRotation, cell);
      ExpectCovered("C", c.position, kMaxRmsPosition, cell);
      ExpectCovered("scale", c.scale, kMaxRmsScale, cell);
    }
  }
}

}  // namespace
}  // namespace rigcal
