// SPDX-License-Identifier: Apache-2.0
// The planar-motion solver and the general/planar decision, batch (CalibrateRig) and online
// (RigEstimator), on car rigs: flat yaw-only drives, a drive up a ramp, and the real KITTI 00
// trajectory (plain and flattened to pure yaw; skipped when the data is absent).
#include <gtest/gtest.h>

#include <cmath>
#include <optional>

#include "rigcal/calib/error_model.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/synthetic_car.h"
#include "support/kitti.h"
#include "support/skip.h"

namespace rigcal {
namespace {

constexpr double kExact = 1e-9;
// Bound on |error| / σ for noisy tests. The motions share poses (pairs overlap and the
// master's noise enters every slave), so the reported σ is a little optimistic; 6 keeps the
// tests from flaking while a wrong model (errors of centimetres to metres) still fails.
constexpr double kSigmas = 6.0;

// A noise-free or noisy car drive along `path`, optionally with odometry re-initialisations.
SyntheticDrive Drive(const SampledTrajectory& path, double rot_noise_deg, double pos_noise,
                     double segment_period_s = 0.0, uint64_t seed = 1) {
  DriveOptions d;
  d.rotation_noise_deg = rot_noise_deg;
  d.position_noise = pos_noise;
  d.segment_period_s = segment_period_s;
  d.seed = seed;
  return DriveCarRig(path, d);
}

SampledTrajectory FlatPath(double duration_s, double rate_hz = 10.0) {
  CarPathOptions o;
  o.duration_s = duration_s;
  o.rate_hz = rate_hz;
  return CarPath(o);
}

// The scale of the slave's segment scales that belongs to `segment` (its estimate.scale for 0).
double ScaleOf(const SlaveCalibration& r, int segment) {
  for (const auto& s : r.scales) {
    if (s.segment == segment) return s.scale;
  }
  return r.estimate.scale;
}

double ScaleStd(const SlaveCalibration& r) { return r.scales.empty() ? 0.0 : r.scales.front().std; }

// In-plane σ: the largest per-axis σ of C (the axis component carries none in the planar
// model, and the master's vertical is its y axis here).
double PlaneStd(const SlaveCalibration& r) { return std::max(r.pos_std.x(), r.pos_std.z()); }

void ExpectWithinSigma(const SlaveCalibration& r, const Similarity& truth) {
  const CalibrationError e = CompareToTruth(r.estimate, truth, r.observability.planar_axis);
  ASSERT_GT(r.rot_std_deg, 0.0) << r.message;
  ASSERT_GT(PlaneStd(r), 0.0) << r.message;
  // Rotation: rot_std_deg is the largest axis' σ; the error has 3 components (2 in the plane).
  EXPECT_LT(e.rot_deg, kSigmas * std::sqrt(3.0) * r.rot_std_deg) << r.name << ": " << r.message;
  EXPECT_LT(e.plane_err, kSigmas * std::sqrt(2.0) * PlaneStd(r)) << r.name << ": " << r.message;
  EXPECT_LT(e.scale_pct / 100.0 * truth.scale, kSigmas * ScaleStd(r) + 1e-12) << r.name;
}

// ---------------------------------------------------------------------------------------------
// Batch, noise-free: the planar model is exact in rotation, scale and in-plane position, and
// reports C along the axis as unknown (0), whatever the cameras' tilt in their own frames.

class ExactPlanar : public ::testing::TestWithParam<std::tuple<Method, double>> {};

TEST_P(ExactPlanar, RecoversEverythingButTheAxisOffset) {
  const auto [method, segment_period] = GetParam();
  const SyntheticDrive drive = Drive(FlatPath(60.0), 0.0, 0.0, segment_period);
  CalibrationOptions o;
  o.method = method;
  const RigCalibration cal = CalibrateRig(drive.recording, o);
  ASSERT_EQ(cal.slaves.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    const SlaveCalibration& r = cal.slaves[i];
    const Similarity& truth = drive.truth[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kPlanar) << r.message;
    EXPECT_TRUE(r.observability.planar);
    EXPECT_EQ(r.observability.tilt_snr, 0.0);  // no noise, no tilt
    ASSERT_EQ(r.unobservable.size(), 1u);
    const Eigen::Vector3d a = r.unobservable[0];
    EXPECT_NEAR(a.dot(Eigen::Vector3d::UnitY()), 1.0, kExact);  // the vertical, sign fixed
    EXPECT_FALSE(r.unobservable_from_prior);
    EXPECT_TRUE(std::isnan(r.axis_offset_std));
    EXPECT_NE(r.message.find("unobservable"), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("unknown"), std::string::npos) << r.message;
    EXPECT_LT(AngleBetween(r.estimate.q, truth.q), kExact) << r.message;
    const Eigen::Vector3d in_plane = truth.C - truth.C.dot(a) * a;
    EXPECT_LT((r.estimate.C - in_plane).norm(), kExact * truth.C.norm()) << r.message;
    EXPECT_EQ(r.estimate.C.dot(a), 0.0);  // reported as 0, not estimated
    // Every segment's scale: segment s has the unit of the first divided by its reset factor,
    // so compare with the noise-free poses' own ratio (GenerateDriveAlong's unit_change).
    EXPECT_NEAR(ScaleOf(r, 0), truth.scale, kExact * truth.scale);
    if (segment_period > 0.0) {
      EXPECT_EQ(r.scale_model, ScaleModel::kSegments);
      EXPECT_GE(r.scales.size(), 2u);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(MethodsAndSegments, ExactPlanar,
                         ::testing::Combine(::testing::Values(Method::kLinear, Method::kNonlinear),
                                            ::testing::Values(0.0, 25.0)));

TEST(PlanarSolver, SegmentScalesAreExact) {
  // Segment scales against the noise-free truth: a re-initialised slave's positions are its
  // first segment's times the reset factor; recover the factor from two poses of the segment.
  const SyntheticDrive drive = Drive(FlatPath(60.0), 0.0, 0.0, 25.0);
  const RigRecording& rec = drive.recording;
  const RigCalibration cal = CalibrateRig(rec, CalibrationOptions{});
  for (size_t i = 0; i < 3; ++i) {
    const SlaveCalibration& r = cal.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    const CameraTrack& track = rec.slaves[i];
    for (const SegmentScale& seg : r.scales) {
      // First and last pose of the segment: master motion = dT slave motion (unit applied).
      size_t first = track.poses.size(), last = 0;
      for (size_t k = 0; k < track.poses.size(); ++k) {
        if (track.segment[k] != seg.segment) continue;
        first = std::min(first, k);
        last = k;
      }
      ASSERT_LT(first, last);
      const Pose master = rec.master.poses[first].Between(rec.master.poses[last]);
      const Pose slave = track.poses[first].Between(track.poses[last]);
      // (I - R_0) dC + s dR C_i = C_0 along the plane: s = |C_0 - (I - R_0) dC| / |C_i|.
      const Eigen::Vector3d lhs =
          master.C - (Eigen::Matrix3d::Identity() - master.R()) * drive.truth[i].C;
      EXPECT_NEAR(seg.scale, lhs.norm() / slave.C.norm(), 1e-9 * seg.scale)
          << r.name << " segment " << seg.segment;
    }
  }
}

TEST(PlanarSolver, NominalMountingFillsTheAxisOffset) {
  const SyntheticDrive drive = Drive(FlatPath(60.0), 0.0, 0.0);
  CalibrationOptions o;
  for (size_t i = 0; i < 3; ++i) {
    Similarity nominal = drive.truth[i];
    nominal.C.y() += 0.05 * (i + 1);  // CAD heights off by 5, 10, 15 cm
    o.nominal[CarRigNames()[i + 1]] = nominal;
  }
  for (double sigma : {0.0, 0.1}) {
    o.nominal_sigma = sigma;
    const RigCalibration cal = CalibrateRig(drive.recording, o);
    for (size_t i = 0; i < 3; ++i) {
      const SlaveCalibration& r = cal.slaves[i];
      const Similarity& nominal = o.nominal.at(r.name);
      ASSERT_TRUE(r.usable()) << r.message;
      ASSERT_EQ(r.motion_model, MotionModel::kPlanar) << r.message;
      const Eigen::Vector3d a = r.unobservable.at(0);
      EXPECT_TRUE(r.unobservable_from_prior);
      EXPECT_NEAR(r.estimate.C.dot(a), nominal.C.dot(a), 1e-12);  // the prior, honoured
      const Eigen::Vector3d in_plane = drive.truth[i].C - drive.truth[i].C.dot(a) * a;
      EXPECT_LT((r.estimate.C - r.estimate.C.dot(a) * a - in_plane).norm(), kExact);
      EXPECT_NE(r.message.find("nominal"), std::string::npos) << r.message;
      if (sigma > 0.0) {
        EXPECT_EQ(r.axis_offset_std, sigma);
        EXPECT_NEAR(r.pos_std.y(), sigma, 1e-6);
      } else {
        EXPECT_TRUE(std::isnan(r.axis_offset_std));
      }
    }
  }
}

TEST(PlanarSolver, ForcedModels) {
  const SyntheticDrive drive = Drive(FlatPath(40.0), 0.02, 0.01);
  CalibrationOptions o;
  o.motion_model = MotionModel::kGeneral;  // the thesis's method cannot do this
  for (const auto& r : CalibrateRig(drive.recording, o).slaves) {
    EXPECT_EQ(r.termination, Termination::kDegenerate) << r.message;
    EXPECT_TRUE(r.observability.planar);
    EXPECT_NE(r.message.find("planar model"), std::string::npos) << r.message;
  }
  o.motion_model = MotionModel::kPlanar;
  const RigCalibration planar = CalibrateRig(drive.recording, o);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(planar.slaves[i].motion_model, MotionModel::kPlanar);
    ExpectWithinSigma(planar.slaves[i], drive.truth[i]);
  }
}

TEST(PlanarSolver, NoisyFlatDriveWithinSigma) {
  const SyntheticDrive drive = Drive(FlatPath(90.0, 20.0), 0.02, 0.01);
  const RigCalibration cal = CalibrateRig(drive.recording, CalibrationOptions{});
  for (size_t i = 0; i < 3; ++i) {
    const SlaveCalibration& r = cal.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kPlanar) << r.message;
    // Noise only: the axes tilt as much as rotation noise explains.
    EXPECT_LT(r.observability.tilt_snr, 3.0);
    EXPECT_GT(r.observability.axis_std_ratio, 100.0);
    EXPECT_NEAR(r.estimate.C.dot(r.unobservable.at(0)), 0.0, 1e-12);
    ExpectWithinSigma(r, drive.truth[i]);
  }
}

TEST(PlanarSolver, GeneralMotionStaysGeneral) {
  DriveOptions d;
  d.num_frames = 800;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"m", "a", "b"}, DemoRig(), d);
  for (const auto& r : CalibrateRig(drive.recording, CalibrationOptions{}).slaves) {
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kGeneral) << r.message;
    EXPECT_FALSE(r.observability.planar);
    EXPECT_TRUE(r.unobservable.empty());
    EXPECT_GT(r.observability.tilt_snr, 100.0);
    EXPECT_LT(r.observability.axis_std_ratio, 3.0);
    EXPECT_TRUE(std::isfinite(r.axis_offset_std));
  }
}

// ---------------------------------------------------------------------------------------------
// The real KITTI 00 trajectory (0.02 deg and 1 cm pose noise): the road's slopes tilt the
// rotation axes enough for the general model, with a large σ along the vertical; flattened to
// pure yaw it is planar.

class Kitti : public ::testing::Test {
 protected:
  void SetUp() override {
    auto kitti = support::LoadKitti00();
    if (!kitti) RIGCAL_SKIP_MISSING() << kitti.error();
    path_ = std::move(*kitti);
  }
  SampledTrajectory path_;
};

// KITTI's turns end many auto pairs at the same pose, which makes the reported σ optimistic
// (shared noise); one pair per end pose keeps σ honest for the checks against it.
CalibrationOptions KittiOptions() {
  CalibrationOptions o;
  o.pairs.max_pairs_per_end = 1;
  return o;
}

TEST_F(Kitti, RealTrajectoryIsNearlyPlanarGeneral) {
  const SyntheticDrive drive = Drive(path_, 0.02, 0.01);
  CalibrationOptions o = KittiOptions();
  // The same pairs with and without the nominal below (auto may choose per σ, which the prior
  // changes): the combined σ is that of the same motions plus the prior.
  o.pairs.policy = PairOptions::Policy::kWalk;
  const RigCalibration cal = CalibrateRig(drive.recording, o);
  for (size_t i = 0; i < 3; ++i) {
    const SlaveCalibration& r = cal.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kGeneral) << r.message;
    EXPECT_TRUE(r.unobservable.empty());
    EXPECT_GT(r.observability.tilt_snr, 10.0) << r.message;
    ExpectWithinSigma(r, drive.truth[i]);
    // The vertical is determined, but far worse than the plane, and the error fits its σ.
    ASSERT_TRUE(std::isfinite(r.axis_offset_std));
    EXPECT_GT(r.axis_offset_std, 10.0 * PlaneStd(r));
    const CalibrationError e =
        CompareToTruth(r.estimate, drive.truth[i], r.observability.planar_axis);
    EXPECT_LT(e.axis_err, kSigmas * r.axis_offset_std) << r.message;
    EXPECT_NE(r.message.find("nearly planar"), std::string::npos) << r.message;
  }
  // A nominal mounting with a σ is combined with the data as a weighted term: the combined σ
  // is that of two independent measurements, and the estimate moves towards the nominal.
  o.nominal_sigma = 0.03;
  for (size_t i = 0; i < 3; ++i) {
    Similarity nominal = drive.truth[i];
    nominal.C.y() += 0.02;
    o.nominal[CarRigNames()[i + 1]] = nominal;
  }
  const RigCalibration with_prior = CalibrateRig(drive.recording, o);
  for (size_t i = 0; i < 3; ++i) {
    const SlaveCalibration& r = with_prior.slaves[i];
    const SlaveCalibration& without = cal.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kGeneral);
    const double combined = 1.0 / std::sqrt(1.0 / std::pow(without.axis_offset_std, 2) +
                                            1.0 / std::pow(o.nominal_sigma, 2));
    EXPECT_NEAR(r.axis_offset_std, combined, 0.2 * combined);
    const Eigen::Vector3d a = r.observability.planar_axis;
    const double h_data = without.estimate.C.dot(a);
    const double h_prior = o.nominal.at(r.name).C.dot(a);
    const double h = r.estimate.C.dot(a);
    EXPECT_LE(h, std::max(h_data, h_prior) + 1e-3);
    EXPECT_GE(h, std::min(h_data, h_prior) - 1e-3);
  }
}

TEST_F(Kitti, FlattenedTrajectoryIsPlanar) {
  const SyntheticDrive drive = Drive(FlattenToYaw(path_), 0.02, 0.01);
  const RigCalibration cal = CalibrateRig(drive.recording, KittiOptions());
  for (size_t i = 0; i < 3; ++i) {
    const SlaveCalibration& r = cal.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kPlanar) << r.message;
    ASSERT_EQ(r.unobservable.size(), 1u);
    EXPECT_GT(std::abs(r.unobservable[0].dot(Eigen::Vector3d::UnitY())), 0.9999);
    EXPECT_NEAR(r.estimate.C.dot(r.unobservable[0]), 0.0, 1e-12);
    ExpectWithinSigma(r, drive.truth[i]);
  }
}

// ---------------------------------------------------------------------------------------------
// Online.

// The online planar estimate is the batch planar linear solution of the same motions (the
// statistics hold the same sums; only the summation order differs).
TEST(PlanarOnline, EqualsBatchPlanarLinearSolution) {
  const SyntheticDrive drive = Drive(FlatPath(60.0, 20.0), 0.02, 0.01, 25.0);
  RigEstimatorOptions o;
  o.gate_after_motions = 1 << 30;
  o.half_life_s = 0.0;
  o.window_size = 1 << 20;
  o.max_open_segments = 100;
  RigEstimator est(CarRigNames(), o);
  for (size_t k = 0; k < drive.recording.size(); ++k) {
    est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
  }
  for (int i = 0; i < 3; ++i) {
    const RefinementJob job = est.MakeRefinementJob(i);
    ASSERT_GT(job.motions.size(), 50u);
    CalibrationOptions batch;
    batch.method = Method::kLinear;
    batch.scale_model = ScaleModel::kSegments;
    batch.alpha_threshold_deg = 0.0;
    batch.outlier_mad_factor = 1e12;
    batch.max_outlier_rounds = 0;
    batch.compute_covariance = false;
    const SlaveCalibration b = CalibrateSlave(job.motions, batch);
    const SlaveCalibration& online = est.Estimate().rig.slaves[i];
    ASSERT_TRUE(b.usable()) << b.message;
    ASSERT_TRUE(online.usable()) << online.message;
    ASSERT_EQ(b.motion_model, MotionModel::kPlanar) << b.message;
    ASSERT_EQ(online.motion_model, MotionModel::kPlanar) << online.message;
    EXPECT_LT(AngleBetween(online.estimate.q, b.estimate.q), 1e-9);
    EXPECT_LT((online.estimate.C - b.estimate.C).norm(), 1e-9 * b.estimate.C.norm());
    ASSERT_EQ(online.scales.size(), b.scales.size());
    for (size_t s = 0; s < b.scales.size(); ++s) {
      EXPECT_NEAR(online.scales[s].scale, b.scales[s].scale, 1e-9 * b.scales[s].scale);
    }
  }
}

// Planar for two and a half minutes, then up a 6 deg ramp: first the vertical offset is flagged
// (planar, unobservable, C along the axis 0), then resolved (general, finite σ, error within
// it), with one switch of the model per slave.
TEST(PlanarOnline, FlagsThenResolvesTheVerticalOffsetOnARamp) {
  CarPathOptions po;
  po.duration_s = 200.0;
  po.ramp_at_s = 150.0;
  const SyntheticDrive drive = Drive(CarPath(po), 0.02, 0.01);
  const RigRecording& rec = drive.recording;
  RigEstimator est(CarRigNames(), RigEstimatorOptions{});
  std::vector<int> switches(3, 0);
  std::vector<uint32_t> last(3, 0);
  std::vector<bool> last_converged(3, false);
  bool checked_before_ramp = false;
  for (size_t k = 0; k < rec.size(); ++k) {
    est.AddSet(rec.t_ns[k], rec.SetAt(k));
    for (int i = 0; i < 3; ++i) {
      const uint32_t flags = est.Estimate().online[i].flags;
      const bool converged = est.Estimate().rig.slaves[i].state == SlaveState::kConverged;
      if (converged && last_converged[i] && ((flags ^ last[i]) & kFlagPlanar)) ++switches[i];
      last[i] = flags;
      last_converged[i] = converged;
    }
    if (!checked_before_ramp && rec.t_ns[k] >= static_cast<int64_t>(149.5e9)) {
      checked_before_ramp = true;
      for (int i = 0; i < 3; ++i) {
        const SlaveCalibration& r = est.Estimate().rig.slaves[i];
        EXPECT_TRUE(est.Estimate().online[i].flags & kFlagPlanar) << r.message;
        EXPECT_TRUE(est.Estimate().rig.slaves[i].state == SlaveState::kConverged) << r.message;
        ASSERT_EQ(r.unobservable.size(), 1u) << r.message;
        EXPECT_NEAR(r.estimate.C.dot(r.unobservable[0]), 0.0, 1e-12);
        EXPECT_TRUE(std::isnan(r.axis_offset_std));
        EXPECT_NE(r.message.find("unobservable"), std::string::npos) << r.message;
      }
    }
  }
  EXPECT_TRUE(checked_before_ramp);
  for (int i = 0; i < 3; ++i) {
    const SlaveCalibration& r = est.Estimate().rig.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_FALSE(est.Estimate().online[i].flags & kFlagPlanar) << r.message;
    EXPECT_EQ(r.motion_model, MotionModel::kGeneral) << r.message;
    EXPECT_TRUE(r.unobservable.empty());
    ASSERT_TRUE(std::isfinite(r.axis_offset_std)) << r.message;
    const CalibrationError e = CompareToTruth(r.estimate, drive.truth[i], Eigen::Vector3d::UnitY());
    EXPECT_LT(e.axis_err, kSigmas * r.axis_offset_std) << r.message;
    EXPECT_LT(e.axis_err, 0.1) << r.message;  // resolved: the heights differ by 0.3-0.4 m
    EXPECT_LE(switches[i], 1) << r.name;
  }
}

// Hysteresis: after the ramp the car keeps driving on the level while old information is
// forgotten, so the tilt fades out of the statistics and the figures drift back through the
// thresholds. With hysteresis the model returns to planar only when the figures are clearly
// planar (a factor 2 beyond the thresholds), much later than without; and it changes only at
// those two events (the ramp, the return), never back and forth.
TEST(PlanarOnline, HysteresisKeepsTheModelFromFlipping) {
  CarPathOptions po;
  po.duration_s = 400.0;
  po.ramp_at_s = 100.0;
  const SyntheticDrive drive = Drive(CarPath(po), 0.02, 0.01);
  struct Run {
    int switches = 0;
    double general_at_s = -1.0, planar_again_at_s = -1.0;
  };
  auto run = [&](double hysteresis) {
    RigEstimatorOptions o;
    o.half_life_s = 60.0;
    o.planar_hysteresis = hysteresis;
    RigEstimator est(CarRigNames(), o);
    Run out;
    bool was_planar = false;
    for (size_t k = 0; k < drive.recording.size(); ++k) {
      est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
      const SlaveCalibration& r = est.Estimate().rig.slaves[0];
      const double t = drive.recording.t_ns[k] * 1e-9;
      if (!r.usable() || t < 10.0) continue;  // the first keyframes decide nothing
      const bool planar = r.motion_model == MotionModel::kPlanar;
      if (t > 10.0 && planar != was_planar) {
        ++out.switches;
        if (!planar && out.general_at_s < 0.0) out.general_at_s = t;
        if (planar && out.general_at_s >= 0.0) out.planar_again_at_s = t;
      }
      was_planar = planar;
    }
    return out;
  };
  const Run without = run(1.0);
  const Run with = run(2.0);
  for (const Run* r : {&without, &with}) {
    EXPECT_GT(r->general_at_s, po.ramp_at_s);  // the ramp makes the vertical observable
    EXPECT_LT(r->general_at_s, po.ramp_at_s + 20.0);
  }
  EXPECT_GT(without.planar_again_at_s, 0.0);  // forgetting brings the figures back
  EXPECT_LE(with.switches, 3);  // planar at t = 10 s, general on the ramp, planar again
  EXPECT_GT(with.planar_again_at_s < 0.0 ? 1e9 : with.planar_again_at_s,
            without.planar_again_at_s + 30.0);
}

TEST(PlanarOnline, NominalKeptThroughRefinementAndStateFiles) {
  const SyntheticDrive drive = Drive(FlatPath(60.0, 20.0), 0.02, 0.01);
  RigEstimatorOptions o;
  o.history_sets = 0;  // the window refinement's axis handling (the batch's is tested above)
  for (size_t i = 0; i < 3; ++i) {
    Similarity nominal = drive.truth[i];
    nominal.C.y() += 0.05;
    o.nominal.push_back(nominal);
  }
  RigEstimator est(CarRigNames(), o);
  for (size_t k = 0; k < drive.recording.size(); ++k) {
    est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
  }
  for (int i = 0; i < 3; ++i) {
    const SlaveCalibration& r = est.Estimate().rig.slaves[i];
    ASSERT_TRUE(r.usable()) << r.message;
    const Eigen::Vector3d a = r.unobservable.at(0);
    EXPECT_TRUE(r.unobservable_from_prior);
    EXPECT_NEAR(r.estimate.C.dot(a), o.nominal[i]->C.dot(a), 1e-12);
    EXPECT_NE(r.message.find("nominal"), std::string::npos) << r.message;
    const RefinementJob job = est.MakeRefinementJob(i);
    const SlaveCalibration refined = RefineWindow(job);
    ASSERT_TRUE(refined.solved());
    EXPECT_NEAR(refined.estimate.C.dot(a), o.nominal[i]->C.dot(a), 1e-9);
    EXPECT_TRUE(est.ApplyRefinement(job, refined));
    EXPECT_TRUE(est.Estimate().online[i].flags & kFlagRefined);
    EXPECT_TRUE(est.Estimate().online[i].flags & kFlagPlanar);
    ExpectWithinSigma(est.Estimate().rig.slaves[i], drive.truth[i]);
  }
  RigEstimator restored(CarRigNames(), o);
  const Status status = restored.RestoreState(est.SaveState());
  ASSERT_TRUE(status.ok()) << status.message();
  for (int i = 0; i < 3; ++i) {
    const SlaveCalibration& a = restored.Estimate().rig.slaves[i];
    EXPECT_EQ(a.motion_model, MotionModel::kPlanar);
    EXPECT_TRUE(restored.Estimate().online[i].flags & kFlagPlanar);
  }
}

}  // namespace
}  // namespace rigcal
