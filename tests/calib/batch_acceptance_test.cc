// SPDX-License-Identifier: Apache-2.0
// Honest states: a result is usable only when the data support it (batch_acceptance in
// calib/src/batch), σ is never silently 0, and an estimate with unknown σ is never converged.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <string>

#include "rigcal/calib/error_model.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/synthetic_car.h"

namespace rigcal {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Quaterniond ExpMap(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle < 1e-15) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle));
}

// A smooth 6-DoF trajectory of random sinusoids (frequencies, phases and amplitudes per axis).
SampledTrajectory RandomTrajectory(uint64_t seed, int frames = 1200, double rate_hz = 20.0) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> freq(0.05, 0.4), phase(0.0, 2.0 * kPi),
      amp_rot(15.0, 40.0), amp_pos(1.0, 3.0);
  double fr[3], pr[3], ar[3], fp[3], pp[3], ap[3];
  for (int a = 0; a < 3; ++a) {
    fr[a] = freq(rng), pr[a] = phase(rng), ar[a] = amp_rot(rng) * kRadPerDeg;
    fp[a] = freq(rng), pp[a] = phase(rng), ap[a] = amp_pos(rng);
  }
  SampledTrajectory out;
  for (int k = 0; k < frames; ++k) {
    const double t = k / rate_hz;
    Eigen::Vector3d rv, pos;
    for (int a = 0; a < 3; ++a) {
      rv[a] = ar[a] * std::sin(2.0 * kPi * fr[a] * t + pr[a]);
      pos[a] = ap[a] * std::sin(2.0 * kPi * fp[a] * t + pp[a]);
    }
    Pose p;
    p.q = ExpMap(rv);
    p.C = pos;
    out.t_ns.push_back(static_cast<int64_t>(std::llround(k * 1e9 / rate_hz)));
    out.poses.push_back(p);
  }
  return out;
}

DriveOptions Noisy() {
  DriveOptions d;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  return d;
}

// Master of one random trajectory, "slave" the master of another: no rig at all.
RigRecording UnrelatedRecording(uint64_t seed_a, uint64_t seed_b) {
  const SyntheticDrive a =
      GenerateDriveAlong({"m", "s"}, {DemoRig()[0]}, RandomTrajectory(seed_a), Noisy());
  DriveOptions other = Noisy();
  other.seed = 7;
  const SyntheticDrive b =
      GenerateDriveAlong({"m", "s"}, {DemoRig()[0]}, RandomTrajectory(seed_b), other);
  RigRecording rec = a.recording;
  rec.slaves[0].poses = b.recording.master.poses;
  rec.slaves[0].segment = b.recording.master.segment;
  return rec;
}

bool Contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(BatchAcceptance, NormalDrivesStayConverged) {
  const SyntheticDrive demo = GenerateDrive({"m", "a", "b"}, DemoRig(), Noisy());
  for (const auto& r : CalibrateRig(demo.recording, CalibrationOptions{}).slaves) {
    EXPECT_EQ(r.state, SlaveState::kConverged) << r.message;
    EXPECT_TRUE(std::isfinite(r.rot_std_deg) && r.rot_std_deg > 0.0) << r.rot_std_deg;
  }
  // Random 6-DoF trajectories of the same rig.
  for (uint64_t seed : {3u, 4u, 5u}) {
    const SyntheticDrive drive =
        GenerateDriveAlong({"m", "s"}, {DemoRig()[1]}, RandomTrajectory(seed), Noisy());
    const auto r = CalibrateRig(drive.recording, CalibrationOptions{}).slaves[0];
    EXPECT_EQ(r.state, SlaveState::kConverged) << "seed " << seed << ": " << r.message;
  }
  // A car on a road (planar model), with drift.
  DriveOptions car = Noisy();
  car.drift_deg_per_frame = 0.002;
  CarPathOptions path;
  path.duration_s = 120.0;
  const SyntheticDrive drive = DriveCarRig(CarPath(path), car);
  for (const auto& r : CalibrateRig(drive.recording, CalibrationOptions{}).slaves) {
    EXPECT_EQ(r.state, SlaveState::kConverged) << r.name << ": " << r.message;
  }
}

TEST(BatchAcceptance, UnrelatedTrajectoriesAreNotUsable) {
  for (const auto& [a, b] : std::vector<std::pair<uint64_t, uint64_t>>{{1, 2}, {3, 4}, {5, 6}}) {
    const auto r = CalibrateRig(UnrelatedRecording(a, b), CalibrationOptions{}).slaves[0];
    EXPECT_FALSE(r.usable()) << r.message;
    EXPECT_EQ(r.state, SlaveState::kInitialising);
    EXPECT_TRUE(Contains(r.message, "not usable")) << r.message;
    std::printf("unrelated %d/%d: %s\n", static_cast<int>(a), static_cast<int>(b),
                r.message.c_str());
  }
}

TEST(BatchAcceptance, ThreePosesAreTooFew) {
  DriveOptions d;
  d.rotation_noise_deg = 0.0;
  d.position_noise = 0.0;
  const SyntheticDrive drive = GenerateDrive({"m", "s"}, {DemoRig()[0]}, d);
  RigRecording rec = drive.recording;
  // Three poses far apart.
  RigRecording three;
  three.master.name = rec.master.name;
  CameraTrack slave;
  slave.name = rec.slaves[0].name;
  for (size_t k : {size_t{0}, size_t{200}, size_t{500}}) {
    three.t_ns.push_back(rec.t_ns[k]);
    three.master.poses.push_back(rec.master.poses[k]);
    three.master.segment.push_back(0);
    slave.poses.push_back(rec.slaves[0].poses[k]);
    slave.segment.push_back(0);
  }
  three.slaves.push_back(slave);
  for (const auto policy : {PairOptions::Policy::kSinceStart, PairOptions::Policy::kAuto}) {
    CalibrationOptions o;
    o.pairs.policy = policy;
    const auto r = CalibrateRig(three, o).slaves[0];
    EXPECT_FALSE(r.usable()) << r.message;
    EXPECT_TRUE(Contains(r.message, "independent motions") ||
                r.termination == Termination::kInsufficientMotion)
        << r.message;
    std::printf("three poses: %s\n", r.message.c_str());
  }
}

TEST(BatchAcceptance, PlanarModelForcedOnGeneralMotionIsNotUsable) {
  const SyntheticDrive drive = GenerateDrive({"m", "s"}, {DemoRig()[0]}, Noisy());
  CalibrationOptions o;
  o.motion_model = MotionModel::kPlanar;
  const auto r = CalibrateRig(drive.recording, o).slaves[0];
  EXPECT_FALSE(r.usable()) << r.message;
  EXPECT_TRUE(Contains(r.message, "not usable")) << r.message;
  std::printf("planar forced: %s\n", r.message.c_str());
}

TEST(BatchAcceptance, TranslationalModelForcedOnRotatingDriveIsNotUsable) {
  const SyntheticDrive drive = GenerateDrive({"m", "s"}, {DemoRig()[0]}, Noisy());
  CalibrationOptions o;
  o.motion_model = MotionModel::kTranslational;
  const auto r = CalibrateRig(drive.recording, o).slaves[0];
  EXPECT_FALSE(r.usable()) << r.message;
  EXPECT_TRUE(Contains(r.message, "not usable")) << r.message;
  std::printf("translational forced: %s\n", r.message.c_str());
}

TEST(BatchAcceptance, UnknownSigmaIsNeverConverged) {
  const SyntheticDrive drive = GenerateDrive({"m", "s"}, {DemoRig()[0]}, Noisy());
  CalibrationOptions o;
  o.compute_covariance = false;
  const auto r = CalibrateRig(drive.recording, o).slaves[0];
  EXPECT_EQ(r.state, SlaveState::kUsable) << r.message;
  EXPECT_TRUE(std::isnan(r.rot_std_deg));
  EXPECT_TRUE(r.pos_std.array().isNaN().all());
  ASSERT_FALSE(r.scales.empty());
  for (const auto& s : r.scales) EXPECT_TRUE(std::isnan(s.std));
}

// A rig standing still: constant poses, exactly or with odometry noise (whose "motions" are
// noise in both cameras).
TEST(OnlineAcceptance, StationaryRigNeverBecomesUsable) {
  for (const double sigma : {0.0, 1e-3}) {
    RigEstimator est({"m", "s"}, RigEstimatorOptions{});
    std::mt19937_64 rng(3);
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int k = 0; k < 2000; ++k) {
      std::vector<std::optional<CameraPose>> set(2);
      for (int c = 0; c < 2; ++c) {
        CameraPose p;
        p.camera = c;
        p.t_ns = static_cast<int64_t>(k) * 50'000'000;
        p.pose.q = ExpMap(sigma * RandomVector3(noise, rng));
        p.pose.C = sigma * RandomVector3(noise, rng);
        set[c] = p;
      }
      est.AddSet(static_cast<int64_t>(k) * 50'000'000, set);
      const SlaveCalibration& s = est.Estimate().rig.slaves[0];
      ASSERT_FALSE(s.usable()) << "noise " << sigma << ", set " << k << ": " << s.message;
    }
    std::printf("stationary, noise %g: %s\n", sigma, est.Estimate().rig.slaves[0].message.c_str());
  }
}

TEST(OnlineAcceptance, UnrelatedTrajectoriesNeverBecomeUsable) {
  const RigRecording rec = UnrelatedRecording(1, 2);
  RigEstimator est({"m", "s"}, RigEstimatorOptions{});
  for (size_t k = 0; k < rec.size(); ++k) {
    est.AddSet(rec.t_ns[k], rec.SetAt(k));
    const SlaveCalibration& s = est.Estimate().rig.slaves[0];
    ASSERT_FALSE(s.usable()) << "set " << k << ": " << s.message;
  }
  const std::string& message = est.Estimate().rig.slaves[0].message;
  EXPECT_TRUE(Contains(message, "not usable: the trajectories are unrelated")) << message;
  std::printf("online unrelated: %s\n", message.c_str());
}

// A car whose one loop takes an hour (a degree of yaw per 20-s odometry segment): the motions
// hardly determine each segment's scale, and fits explain them with a wrong rotation and a
// negative or vanishing scale. A scale maps one positive unit to another: such an estimate is
// never usable, whatever its σ (the refinement published as the node's thread does it).
TEST(OnlineAcceptance, NoScaleBelowZeroIsUsable) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kPlanarYaw;
  d.num_frames = 150 * 20;
  d.period_s = 3600.0;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.005;
  d.segment_period_s = 20.0;
  const std::vector<Similarity> rigs = {
      {Eigen::Quaterniond(std::sqrt(0.5), 0.0, -std::sqrt(0.5), 0.0), {-0.9, 0.1, -1.6}, 1.0},
      {Eigen::Quaterniond(0.0, 0.0, 1.0, 0.0), {0.0, 0.2, -3.9}, 1.0},
      {Eigen::Quaterniond(std::sqrt(0.5), 0.0, std::sqrt(0.5), 0.0), {0.9, 0.1, -1.6}, 1.0}};
  const SyntheticDrive drive = GenerateDrive({"front", "left", "back", "right"}, rigs, d);
  RigEstimator est({"front", "left", "back", "right"}, RigEstimatorOptions{});
  int usable_sets = 0, negative_fits = 0;
  for (size_t k = 0; k < drive.recording.size(); ++k) {
    est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
    if (k % 40 == 39) {  // every 2 s, as the refinement thread
      for (int i = 0; i < 3; ++i) {
        const RefinementJob job = est.MakeRefinementJob(i);
        if (!job.start.solved()) continue;
        est.ApplyRefinement(job, RefineWindow(job));
      }
    }
    for (const SlaveCalibration& s : est.Estimate().rig.slaves) {
      bool negative = s.solved() && !(s.estimate.scale > 0.0);
      for (const SegmentScale& seg : s.scales) negative = negative || !(seg.scale > 0.0);
      negative_fits += negative ? 1 : 0;
      usable_sets += s.usable() ? 1 : 0;
      ASSERT_FALSE(negative && s.usable())
          << s.name << " at set " << k << ": scale " << s.estimate.scale << ", " << s.message;
    }
  }
  // The drive does produce such fits (else the test tests nothing).
  EXPECT_GT(negative_fits, 0);
  std::printf("hour-long loop, 150 s: %d slave estimates with a scale <= 0, %d usable ones\n",
              negative_fits, usable_sets);
}

}  // namespace
}  // namespace rigcal
