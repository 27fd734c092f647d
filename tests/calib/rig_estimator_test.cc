// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/rig_estimator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || defined(RIGCAL_ASAN) || \
    defined(RIGCAL_TSAN)
constexpr bool kSanitized = true;
#else
constexpr bool kSanitized = false;
#endif

std::vector<std::string> Names(const RigRecording& rec) {
  std::vector<std::string> names = {rec.master.name};
  for (const auto& s : rec.slaves) names.push_back(s.name);
  return names;
}

void Feed(RigEstimator* est, const RigRecording& rec, size_t from = 0, size_t to = SIZE_MAX) {
  for (size_t k = from; k < std::min(to, rec.size()); ++k) est->AddSet(rec.t_ns[k], rec.SetAt(k));
}

SyntheticDrive NoisyDrive(int frames, uint64_t seed = 1, int slaves = 2) {
  DriveOptions d;
  d.num_frames = frames;
  d.seed = seed;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  std::vector<Similarity> rigs = DemoRig();
  rigs.resize(slaves, rigs[0]);
  std::vector<std::string> names = {"front", "left", "back", "right"};
  names.resize(slaves + 1);
  return GenerateDrive(names, rigs, d);
}

// Online estimate == batch linear least squares of the same motions (forgetting, gating and
// Huber weights off). The sums are the same; only the summation order differs, so the
// difference is at rounding level.
TEST(RigEstimator, EqualsBatchLinearSolution) {
  for (double segment_period : {0.0, 20.0}) {
    DriveOptions d;
    d.num_frames = 1200;
    d.rotation_noise_deg = 0.05;
    d.position_noise = 0.002;
    d.segment_period_s = segment_period;
    const SyntheticDrive drive = GenerateDrive({"m", "a", "b"}, DemoRig(), d);
    RigEstimatorOptions o;
    o.gate_after_motions = 1 << 30;
    o.half_life_s = 0.0;
    o.window_size = 1 << 20;
    o.max_open_segments = 100;
    RigEstimator est(Names(drive.recording), o);
    Feed(&est, drive.recording);
    for (int i = 0; i < 2; ++i) {
      const RefinementJob job = est.MakeRefinementJob(i);
      ASSERT_GT(job.motions.size(), 50u);
      CalibrationOptions batch;
      batch.method = Method::kLinear;
      batch.motion_model = MotionModel::kGeneral;
      batch.scale_model = ScaleModel::kSegments;
      batch.alpha_threshold_deg = 0.0;
      batch.outlier_mad_factor = 1e12;
      batch.max_outlier_rounds = 0;
      batch.compute_covariance = false;
      const SlaveCalibration b = CalibrateSlave(job.motions, batch);
      const SlaveCalibration& online = est.Estimate().rig.slaves[i];
      ASSERT_TRUE(b.usable()) << b.message;
      ASSERT_TRUE(online.usable()) << online.message;
      EXPECT_LT(AngleBetween(online.estimate.q, b.estimate.q), 1e-9);
      EXPECT_LT((online.estimate.C - b.estimate.C).norm(), 1e-9 * b.estimate.C.norm());
      ASSERT_EQ(online.scales.size(), b.scales.size());
      for (size_t s = 0; s < b.scales.size(); ++s) {
        EXPECT_EQ(online.scales[s].segment, b.scales[s].segment);
        EXPECT_NEAR(online.scales[s].scale, b.scales[s].scale, 1e-9 * b.scales[s].scale);
      }
    }
  }
}

long ResidentKiB() {
  std::ifstream statm("/proc/self/statm");
  long pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * 4;
}

// 1e6 sets: memory must stay flat after the first keyframes fill the bounded buffers.
TEST(RigEstimator, MemoryStaysBounded) {
  if (kSanitized)
    GTEST_SKIP() << "sanitizer runtimes keep freed memory in quarantine: RSS is not "
                    "the estimator's footprint";
  const SyntheticDrive drive = NoisyDrive(2000);  // periodic: frame 2000 == frame 0
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  const int64_t period = drive.recording.t_ns.back() + 50'000'000;
  const size_t total = 400'000;  // 200 passes over the drive
  long rss_after_warmup = 0;
  for (size_t n = 0; n < total; ++n) {
    const size_t k = n % drive.recording.size();
    const int64_t offset = static_cast<int64_t>(n / drive.recording.size()) * period;
    auto set = drive.recording.SetAt(k);
    for (auto& pose : set) pose->t_ns += offset;  // the drive again, later
    est.AddSet(drive.recording.t_ns[k] + offset, set);
    if (n == total / 10) rss_after_warmup = ResidentKiB();
  }
  const long growth = ResidentKiB() - rss_after_warmup;
  EXPECT_LT(growth, 2048) << "RSS grew by " << growth << " KiB";
  EXPECT_EQ(est.Estimate().sets, total);
  EXPECT_TRUE(est.Estimate().rig.slaves[0].usable());
}

TEST(RigEstimator, ConvergesOnGeneralDrive) {
  const SyntheticDrive drive = NoisyDrive(2400);
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording);
  for (int i = 0; i < 2; ++i) {
    const auto& r = est.Estimate().rig.slaves[i];
    const auto& online = est.Estimate().online[i];
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.state, SlaveState::kConverged) << r.message;
    EXPECT_EQ(online.decalibration_events, 0);
    const auto e = CompareToTruth(r.estimate, drive.truth[i]);
    EXPECT_LT(e.rot_deg, 0.2) << r.message;
    EXPECT_LT(e.trans_err, 0.03);
    EXPECT_LT(e.scale_pct, 1.0);
    // The reported sigma is of the right order: the error is within 6 sigma per axis.
    EXPECT_LT(e.rot_deg, 6 * std::sqrt(3.0) * r.rot_std_deg + 0.01);
  }
}

// RMS over drives (seeds first_seed, first_seed + 1, ...) of the online rotation error per σ
// (σ of the largest axis, the error the whole angle: √3 per axis for an isotropic error).
// Infinite when a drive ends without a usable estimate with a finite σ > 0, or in another
// motion model than `model`.
double OnlineRotationErrorPerSigmaRms(const Similarity& rig, const DriveOptions& base,
                                      const RigEstimatorOptions& options, int trials,
                                      uint64_t first_seed, MotionModel model) {
  double sum_sq = 0.0;
  for (int t = 0; t < trials; ++t) {
    DriveOptions d = base;
    d.seed = first_seed + t;
    const SyntheticDrive drive = GenerateDrive({"front", "back"}, {rig}, d);
    RigEstimator est(Names(drive.recording), options);
    Feed(&est, drive.recording);
    const auto& r = est.Estimate().rig.slaves[0];
    EXPECT_TRUE(r.usable()) << r.message;
    EXPECT_EQ(r.motion_model, model) << r.message;
    if (!r.usable() || r.motion_model != model || !(r.rot_std_deg > 0.0) ||
        !std::isfinite(r.rot_std_deg)) {
      return std::numeric_limits<double>::infinity();
    }
    const double e = CompareToTruth(r.estimate, drive.truth[0]).rot_deg;
    sum_sq += std::pow(e / (std::sqrt(3.0) * r.rot_std_deg), 2);
  }
  return std::sqrt(sum_sq / trials);
}

// Drifting odometry (a random walk of the orientation) makes the errors of motions close in
// time alike. The published rotation σ counts it (time blocks): the RMS over drives of the
// error per σ (σ of the largest axis, the error the whole angle, √3 per axis) is near 1, while
// with the blocks off it is far above.
TEST(RigEstimator, RotationSigmaWithDriftingOdometry) {
  DriveOptions d;
  d.num_frames = 2400;
  d.rotation_noise_deg = 0.02;
  d.position_noise = 0.002;
  d.drift_deg_per_frame = 0.01;
  auto rms = [&](const RigEstimatorOptions& options) {
    return OnlineRotationErrorPerSigmaRms(DemoRig()[0], d, options, 16, 700, MotionModel::kGeneral);
  };
  RigEstimatorOptions independent;
  independent.sigma_block_s = 0.0;
  const double without = rms(independent);
  const double with_blocks = rms(RigEstimatorOptions{});
  std::printf("online, drifting odometry: RMS error / sigma %.2f without time blocks, %.2f with\n",
              without, with_blocks);
  EXPECT_GT(with_blocks, 0.4);
  EXPECT_LT(with_blocks, 2.0);
  EXPECT_GT(without, 1.5 * with_blocks);
}

TEST(RigEstimator, PlanarDriveFlagsVerticalOffset) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kPlanarYaw;
  d.num_frames = 1600;
  d.rotation_noise_deg = 0.02;
  d.position_noise = 0.001;
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {DemoRig()[0]}, d);
  RigEstimatorOptions o;
  Similarity nominal = drive.truth[0];
  nominal.C.y() += 0.05;  // CAD value 5 cm off along the (unobservable) vertical
  o.nominal = {nominal};
  RigEstimator est(Names(drive.recording), o);
  Feed(&est, drive.recording);
  const auto& r = est.Estimate().rig.slaves[0];
  EXPECT_TRUE(est.Estimate().online[0].flags & kFlagPlanar) << r.message;
  ASSERT_FALSE(r.unobservable.empty());
  EXPECT_NEAR(std::abs(r.unobservable.back().dot(Eigen::Vector3d::UnitY())), 1.0, 1e-3);
  EXPECT_NE(r.message.find("unobservable"), std::string::npos);
  const Eigen::Vector3d axis = r.unobservable.back().normalized();
  EXPECT_NEAR(r.estimate.C.dot(axis), nominal.C.dot(axis), 1e-9);
}

TEST(RigEstimator, PureTranslationGivesRotationAndScaleOnly) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kTranslationOnly;
  d.num_frames = 1200;
  d.rotation_noise_deg = 0.02;
  d.position_noise = 0.001;
  const SyntheticDrive drive = GenerateDrive({"front", "back"}, {DemoRig()[1]}, d);
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording);
  const auto& r = est.Estimate().rig.slaves[0];
  ASSERT_TRUE(r.usable()) << r.message;
  EXPECT_TRUE(est.Estimate().online[0].flags & kFlagTranslationalOnly);
  EXPECT_FALSE(r.position_observable);
  const auto e = CompareToTruth(r.estimate, drive.truth[0]);
  EXPECT_LT(e.rot_deg, 0.5);
  EXPECT_LT(e.scale_pct, 2.0);
}

// The translational model's σ (Horn on translation directions) is of the size of its error:
// the RMS over seeds of the error per σ (σ of the largest axis, the error the whole angle:
// √3 per axis for an isotropic error) lies within a factor ~2 of 1.
TEST(RigEstimator, PureTranslationSigmaMatchesError) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kTranslationOnly;
  d.num_frames = 1200;
  d.rotation_noise_deg = 0.02;
  d.position_noise = 0.004;
  constexpr int kSeeds = 12;
  const double rms = OnlineRotationErrorPerSigmaRms(DemoRig()[1], d, RigEstimatorOptions{}, kSeeds,
                                                    1, MotionModel::kTranslational);
  std::printf("translational model: RMS of error / sigma over %d seeds: %.2f\n", kSeeds, rms);
  EXPECT_GT(rms, 0.4);
  EXPECT_LT(rms, 2.0);
}

// Translations all along one line do not determine the rotation about it: the σ says so
// (no small number) and the estimate is not usable (initialising, as the batch calibrator's
// degenerate result), never converged.
TEST(RigEstimator, StraightDriveDoesNotConverge) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kStraight;
  d.num_frames = 1200;
  d.rotation_noise_deg = 0.02;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "back"}, {DemoRig()[1]}, d);
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording);
  const auto& r = est.Estimate().rig.slaves[0];
  ASSERT_TRUE(r.solved()) << r.message;
  EXPECT_FALSE(r.usable()) << r.message;
  EXPECT_NE(r.message.find("not usable: the rotation is not determined"), std::string::npos)
      << r.message;
  EXPECT_EQ(r.motion_model, MotionModel::kTranslational);
  EXPECT_GT(r.rot_std_deg, 5.0) << r.message << "; error "
                                << CompareToTruth(r.estimate, drive.truth[0]).rot_deg;
  EXPECT_FALSE(est.Estimate().rig.slaves[0].state == SlaveState::kConverged) << r.message;
  EXPECT_NE(r.message.find("undetermined"), std::string::npos) << r.message;
}

TEST(RigEstimator, ScaleSegmentsFromOdometryResets) {
  DriveOptions d;
  d.num_frames = 3600;  // 3 minutes, a reset every 30 s
  d.segment_period_s = 30.0;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {DemoRig()[0]}, d);
  DriveOptions clean = d;
  clean.rotation_noise_deg = 0.0;
  clean.position_noise = 0.0;
  const SyntheticDrive exact = GenerateDrive({"front", "left"}, {DemoRig()[0]}, clean);
  // Noise-free batch calibration recovers the segment scales exactly (rig_calibrator_test).
  const SlaveCalibration truth = CalibrateRig(exact.recording, CalibrationOptions{}).slaves[0];
  ASSERT_EQ(truth.scales.size(), 6u) << truth.message;

  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording);
  const auto& r = est.Estimate().rig.slaves[0];
  ASSERT_TRUE(r.usable()) << r.message;
  EXPECT_EQ(est.Estimate().online[0].segment, 5);
  ASSERT_EQ(r.scales.size(), 6u);  // closed (marginalised) and open segments
  for (size_t s = 0; s < 6; ++s) {
    EXPECT_EQ(r.scales[s].segment, static_cast<int>(s));
    EXPECT_NEAR(r.scales[s].scale / truth.scales[s].scale, 1.0, 0.02) << "segment " << s;
  }
  EXPECT_NEAR(r.estimate.scale / truth.scales[5].scale, 1.0, 0.02);
  EXPECT_LT(CompareToTruth(r.estimate, drive.truth[0]).rot_deg, 0.2);
}

TEST(RigEstimator, BumpedCameraIsFlaggedAndFollowed) {
  DriveOptions d;
  d.num_frames = 4800;  // 4 minutes; the left camera is knocked by 2 deg at 2 minutes
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  Similarity bumped = DemoRig()[0];
  bumped.q = AxisAngle(Eigen::Vector3d(0.3, 1.0, -0.2), 2.0 * kRadPerDeg) * bumped.q;
  d.change_frame = 2400;
  d.changed_rigs = {bumped};
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {DemoRig()[0]}, d);
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording, 0, 2400);
  ASSERT_TRUE(est.Estimate().rig.slaves[0].state == SlaveState::kConverged);
  EXPECT_LT(CompareToTruth(est.Estimate().rig.slaves[0].estimate, drive.truth[0]).rot_deg, 0.2);
  bool flagged = false;
  for (size_t k = 2400; k < drive.recording.size(); ++k) {
    est.AddSet(drive.recording.t_ns[k], drive.recording.SetAt(k));
    flagged = flagged || (est.Estimate().rig.slaves[0].state == SlaveState::kDecalibrated);
  }
  EXPECT_TRUE(flagged);
  EXPECT_GE(est.Estimate().online[0].decalibration_events, 1);
  const auto& r = est.Estimate().rig.slaves[0];
  EXPECT_LT(CompareToTruth(r.estimate, bumped).rot_deg, 0.3) << r.message;
  EXPECT_TRUE(est.Estimate().rig.slaves[0].state == SlaveState::kConverged) << r.message;
}

TEST(RigEstimator, GarbagePosesDoNotMoveTheEstimate) {
  SyntheticDrive drive = NoisyDrive(2400, 3, 1);
  RigEstimator clean(Names(drive.recording), RigEstimatorOptions{});
  Feed(&clean, drive.recording);
  std::mt19937_64 rng(5);
  auto& poses = drive.recording.slaves[0].poses;
  for (size_t k = 7; k < poses.size(); k += 20) {  // 5 % garbage
    poses[k].q = AxisAngle(RandomUnitVector(rng), 0.8) * poses[k].q;
    poses[k].C += RandomUnitVector(rng) * 1.5;
  }
  RigEstimator dirty(Names(drive.recording), RigEstimatorOptions{});
  Feed(&dirty, drive.recording);
  const auto e_clean = CompareToTruth(clean.Estimate().rig.slaves[0].estimate, drive.truth[0]);
  const auto& r = dirty.Estimate().rig.slaves[0];
  const auto e_dirty = CompareToTruth(r.estimate, drive.truth[0]);
  EXPECT_GT(r.glitches.dropped() + r.motions.rejected(), 0);  // skipped or gated
  EXPECT_LT(e_dirty.rot_deg, 3 * e_clean.rot_deg + 0.05) << r.message;
  EXPECT_LT(e_dirty.trans_err, 3 * e_clean.trans_err + 0.01);
}

TEST(RigEstimator, WindowRefinementIsPublishedWhenConsistent) {
  const SyntheticDrive drive = NoisyDrive(1600, 8, 1);
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording);
  const auto linear = est.Estimate().rig.slaves[0];
  const RefinementJob job = est.MakeRefinementJob(0);
  const SlaveCalibration refined = RefineWindow(job);
  ASSERT_TRUE(refined.solved());
  EXPECT_TRUE(est.ApplyRefinement(job, refined));
  EXPECT_TRUE(est.Estimate().online[0].flags & kFlagRefined);
  const auto e_lin = CompareToTruth(linear.estimate, drive.truth[0]);
  const auto e_nl = CompareToTruth(est.Estimate().rig.slaves[0].estimate, drive.truth[0]);
  EXPECT_LT(e_nl.rot_deg, 2 * e_lin.rot_deg + 0.02);
  // A job made before a reset of the statistics is refused.
  RefinementJob stale = job;
  stale.generation = job.generation + 1;
  EXPECT_FALSE(est.ApplyRefinement(stale, refined));
}

// The window refinement's prior holds exactly what the statistics know of the motions outside
// the window: a short window with its prior minimises the same sum of squares as a window of
// every motion, and after a restart from a state file (no window at all) the prior alone does.
TEST(RigEstimator, WindowPriorMakesAShortWindowRefineLikeAllMotions) {
  const SyntheticDrive drive = NoisyDrive(1600, 11, 1);
  const auto names = Names(drive.recording);
  RigEstimatorOptions all;
  all.window_size = 1 << 20;
  all.gate_after_motions = 1 << 30;  // no Huber weights in the statistics
  all.history_sets = 0;              // the window refinement, not the batch on the history
  RigEstimatorOptions short_window = all;
  short_window.window_size = 20;
  RigEstimator a(names, all), b(names, short_window);
  Feed(&a, drive.recording);
  Feed(&b, drive.recording);
  RefinementJob job_all = a.MakeRefinementJob(0);
  RefinementJob job_short = b.MakeRefinementJob(0);
  EXPECT_EQ(job_all.prior.motions, 0);
  ASSERT_EQ(job_short.motions.size(), 20u);
  ASSERT_GT(job_all.motions.size(), 200u);
  EXPECT_EQ(job_short.prior.motions + 20, static_cast<int>(job_all.motions.size()));
  RefinementJob job_window_only = job_short;
  job_window_only.prior = RefinementPrior{};
  for (RefinementJob* job : {&job_all, &job_short, &job_window_only}) job->robust_loss = false;
  const SlaveCalibration r_all = RefineWindow(job_all);
  const SlaveCalibration r_short = RefineWindow(job_short);
  const SlaveCalibration r_window_only = RefineWindow(job_window_only);
  ASSERT_TRUE(r_all.solved() && r_short.solved() && r_window_only.solved());
  ASSERT_GT(r_all.rot_std_deg, 0.0);
  // The same minimum up to rounding (the sums are accumulated in another order).
  EXPECT_LT(AngleBetween(r_short.estimate.q, r_all.estimate.q), 1e-9);
  EXPECT_LT((r_short.estimate.C - r_all.estimate.C).norm(), 1e-9 * r_all.estimate.C.norm());
  EXPECT_NEAR(r_short.estimate.scale, r_all.estimate.scale, 1e-9 * r_all.estimate.scale);
  // ... and the uncertainty of every motion, not of the 20.
  EXPECT_NEAR(r_short.rot_std_deg, r_all.rot_std_deg, 1e-6 * r_all.rot_std_deg);
  // 20 motions alone are far noisier.
  EXPECT_GT(AngleBetween(r_window_only.estimate.q, r_all.estimate.q) * kDegPerRad,
            3.0 * r_all.rot_std_deg);

  // With the Huber loss on the window's residuals (the default) the minimum moves by a small
  // part of the uncertainty.
  job_short.robust_loss = true;
  const SlaveCalibration r_robust = RefineWindow(job_short);
  EXPECT_LT(AngleBetween(r_robust.estimate.q, r_all.estimate.q) * kDegPerRad,
            0.5 * r_all.rot_std_deg);

  // Restarted from its state: the window is empty, the prior holds everything.
  RigEstimator c(names, short_window);
  const Status restored = c.RestoreState(b.SaveState());
  ASSERT_TRUE(restored.ok()) << restored.message();
  RefinementJob job_restored = c.MakeRefinementJob(0);
  EXPECT_TRUE(job_restored.motions.empty());
  EXPECT_EQ(job_restored.prior.motions, static_cast<int>(job_all.motions.size()));
  const SlaveCalibration r_restored = RefineWindow(job_restored);
  ASSERT_TRUE(r_restored.solved());
  EXPECT_LT(AngleBetween(r_restored.estimate.q, r_all.estimate.q), 1e-9);
  EXPECT_LT((r_restored.estimate.C - r_all.estimate.C).norm(), 1e-9 * r_all.estimate.C.norm());
}

// With forgetting and scale segments that close (marginalised), the window and its prior
// still add up to the long statistics: the prior-only refinement after a restart equals the
// refinement with the window.
TEST(RigEstimator, WindowPriorFollowsForgettingAndClosedSegments) {
  DriveOptions d;
  d.num_frames = 3000;
  d.seed = 12;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  d.segment_period_s = 30.0;
  std::vector<Similarity> rigs = DemoRig();
  rigs.resize(1);
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, rigs, d);
  RigEstimatorOptions o;
  o.window_size = 50;
  o.history_sets = 0;  // the window refinement, not the batch on the history
  o.half_life_s = 60.0;
  o.gate_after_motions = 1 << 30;
  RigEstimator est(Names(drive.recording), o);
  Feed(&est, drive.recording);
  RefinementJob job = est.MakeRefinementJob(0);
  job.robust_loss = false;
  ASSERT_EQ(job.motions.size(), 50u);
  ASSERT_GT(job.prior.motions, 50);
  EXPECT_LE(job.prior.segments.size(), static_cast<size_t>(o.max_open_segments));
  const SlaveCalibration with_window = RefineWindow(job);
  RigEstimator restored(Names(drive.recording), o);
  const Status status = restored.RestoreState(est.SaveState());
  ASSERT_TRUE(status.ok()) << status.message();
  RefinementJob prior_only = restored.MakeRefinementJob(0);
  prior_only.robust_loss = false;
  ASSERT_TRUE(prior_only.motions.empty());
  const SlaveCalibration from_prior = RefineWindow(prior_only);
  ASSERT_TRUE(with_window.solved() && from_prior.solved());
  EXPECT_LT(AngleBetween(with_window.estimate.q, from_prior.estimate.q), 1e-8);
  EXPECT_LT((with_window.estimate.C - from_prior.estimate.C).norm(),
            1e-8 * with_window.estimate.C.norm());
  EXPECT_NEAR(with_window.estimate.scale, from_prior.estimate.scale, 1e-8);
  const auto error_nl = CompareToTruth(with_window.estimate, drive.truth[0]);
  EXPECT_LT(error_nl.rot_deg, 6.0 * with_window.rot_std_deg);
}

// The prior also enters the reduced parameters of the planar model (C in the plane, the
// offset along the axis held) and the translational model (no C).
TEST(RigEstimator, WindowPriorWithPlanarAndTranslationalModels) {
  for (const auto motion :
       {DriveOptions::Motion::kPlanarYaw, DriveOptions::Motion::kTranslationOnly}) {
    DriveOptions d;
    d.motion = motion;
    d.num_frames = 2400;
    d.seed = 13;
    d.rotation_noise_deg = 0.02;
    d.position_noise = 0.002;
    std::vector<Similarity> rigs = DemoRig();
    rigs.resize(1);
    const SyntheticDrive drive = GenerateDrive({"front", "left"}, rigs, d);
    RigEstimatorOptions all;
    all.window_size = 1 << 20;
    all.gate_after_motions = 1 << 30;
    RigEstimatorOptions short_window = all;
    short_window.window_size = 20;
    RigEstimator a(Names(drive.recording), all), b(Names(drive.recording), short_window);
    Feed(&a, drive.recording);
    Feed(&b, drive.recording);
    RefinementJob job_all = a.MakeRefinementJob(0), job_short = b.MakeRefinementJob(0);
    job_all.robust_loss = job_short.robust_loss = false;
    ASSERT_GT(job_short.prior.motions, 0);
    const SlaveCalibration r_all = RefineWindow(job_all), r_short = RefineWindow(job_short);
    ASSERT_TRUE(r_all.solved() && r_short.solved()) << r_all.message;
    EXPECT_EQ(r_all.motion_model, motion == DriveOptions::Motion::kPlanarYaw
                                      ? MotionModel::kPlanar
                                      : MotionModel::kTranslational);
    EXPECT_LT(AngleBetween(r_short.estimate.q, r_all.estimate.q), 1e-8) << r_all.message;
    EXPECT_LT((r_short.estimate.C - r_all.estimate.C).norm(), 1e-8) << r_all.message;
    EXPECT_NEAR(r_short.estimate.scale, r_all.estimate.scale, 1e-8 * r_all.estimate.scale);
  }
}

// The state as plain data: a fresh estimator continues from it; a state of other cameras or
// with another number of slaves is rejected with a message and changes nothing. (The state
// file is tests/io/estimator_state_file_test.cc.)
TEST(RigEstimator, RestoresItsStateAndRejectsForeignOnes) {
  const SyntheticDrive drive = NoisyDrive(1200, 4, 2);
  const auto names = Names(drive.recording);
  RigEstimator est(names, RigEstimatorOptions{});
  Feed(&est, drive.recording);
  const RigEstimatorState state = est.SaveState();
  ASSERT_EQ(state.cameras, names);
  ASSERT_EQ(state.slaves.size(), 2u);
  EXPECT_EQ(state.slaves[0].counts.used, est.Estimate().rig.slaves[0].motions.used);
  EXPECT_GT(state.slaves[0].long_stats.motions, 0);

  RigEstimator restored(names, RigEstimatorOptions{});
  const Status ok = restored.RestoreState(state);
  ASSERT_TRUE(ok.ok()) << ok.message();
  for (int i = 0; i < 2; ++i) {
    const SlaveCalibration& before = est.Estimate().rig.slaves[i];
    const SlaveCalibration& after = restored.Estimate().rig.slaves[i];
    EXPECT_EQ(after.motions.used, before.motions.used);
    EXPECT_EQ(after.motion_model, before.motion_model);
    EXPECT_LT(AngleBetween(after.estimate.q, before.estimate.q), 1e-12);
    EXPECT_LT((after.estimate.C - before.estimate.C).norm(), 1e-12);
  }
  EXPECT_EQ(restored.SaveState().slaves[1].long_stats.rotation,
            state.slaves[1].long_stats.rotation);

  RigEstimator fresh(names, RigEstimatorOptions{});
  RigEstimatorState renamed = state;
  renamed.cameras[2] = "rear";
  const Status foreign = fresh.RestoreState(renamed);
  EXPECT_FALSE(foreign.ok());
  EXPECT_NE(foreign.message().find("different rig (camera 'back')"), std::string::npos)
      << foreign.message();
  RigEstimator other_rig({"front", "left", "back", "rear"}, RigEstimatorOptions{});
  EXPECT_NE(other_rig.RestoreState(state).message().find("different rig"), std::string::npos);
  RigEstimatorState missing_slave = state;
  missing_slave.slaves.pop_back();
  const Status inconsistent = fresh.RestoreState(missing_slave);
  EXPECT_FALSE(inconsistent.ok());
  EXPECT_NE(inconsistent.message().find("1 slaves for 2"), std::string::npos)
      << inconsistent.message();
  EXPECT_EQ(fresh.Estimate().rig.slaves[0].motions.used, 0);  // unchanged
  EXPECT_EQ(fresh.SaveState().slaves[0].long_stats.motions, 0);
}

TEST(RigEstimator, BadSetsAreCountedAndIgnored) {
  const SyntheticDrive drive = NoisyDrive(1200, 6, 1);
  RigEstimator est(Names(drive.recording), RigEstimatorOptions{});
  Feed(&est, drive.recording, 0, 800);
  const auto before = est.Estimate().rig.slaves[0].estimate;
  auto set = drive.recording.SetAt(10);  // time going backwards
  est.AddSet(drive.recording.t_ns[10], set);
  auto nan_master = drive.recording.SetAt(801);
  nan_master[0]->pose.C.x() = std::nan("");
  est.AddSet(drive.recording.t_ns[801], nan_master);
  est.AddSet(drive.recording.t_ns[802], {});  // empty set
  EXPECT_EQ(est.Estimate().rejected_sets, 3u);
  auto nan_slave = drive.recording.SetAt(803);
  nan_slave[1]->pose.q.w() = std::nan("");
  est.AddSet(drive.recording.t_ns[803], nan_slave);
  const auto after = est.Estimate().rig.slaves[0].estimate;
  EXPECT_LT(AngleBetween(before.q, after.q), 1e-12);
  EXPECT_GE(est.Estimate().rig.slaves[0].motions.residual_outlier, 1);
}

TEST(RigEstimatorOptions, CheckNamesField) {
  RigEstimatorOptions o;
  EXPECT_TRUE(o.Check().ok()) << o.Check().message();
  o.window_size = 1;
  const Status status = o.Check();
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message().find("window_size"), std::string::npos);
  EXPECT_EQ(status.message(), "window_size: must be >= 2");
  // The estimator rejects invalid options instead of running with them.
  try {
    RigEstimator est({"front", "left"}, o);
    ADD_FAILURE() << "invalid options accepted";
  } catch (const InvalidOptions& e) {
    EXPECT_STREQ(e.what(), "RigEstimatorOptions: window_size: must be >= 2");
  }
}

TEST(RigEstimatorOptions, DecalibrationConfirmationIsADuration) {
  for (const double bad : {-0.1, std::nan(""), 1e300}) {
    RigEstimatorOptions o;
    o.decalibration_confirm_s = bad;
    EXPECT_EQ(o.Check().message(), "decalibration_confirm_s: must be in [0, 86400] seconds") << bad;
  }
  RigEstimatorOptions o;
  o.decalibration_confirm_s = 0.0;  // keyframes alone
  EXPECT_TRUE(o.Check().ok());
  // No keyframe in disagreement would raise the alarm at every comparison.
  o.decalibration_confirmations = 0;
  EXPECT_EQ(o.Check().message(), "decalibration_confirmations: must be >= 1");
}

}  // namespace
}  // namespace rigcal

namespace rigcal {
namespace {

// The pose history: while it holds every set, the background refinement is the batch
// calibrator on those sets (its pair choice and time-block σ, not inflated again), so the
// online estimate ends exactly where the batch one does; when it has dropped sets, the window
// refinement of the statistics; between due times, no job.
// The history refinement (the published value) decides the motion model with the online
// options' model selection: a planar drive is planar by default, and general online and in the
// history refinement when the config asks for little axis tilt (min_tilt_snr).
TEST(RigEstimatorHistory, ConfigModelSelectionReachesTheHistoryRefinement) {
  DriveOptions d;
  d.motion = DriveOptions::Motion::kPlanarYaw;
  d.num_frames = 1200;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.001;
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {DemoRig()[0]}, d);
  auto published_model = [&](const RigEstimatorOptions& o) {
    RigEstimator est(Names(drive.recording), o);
    Feed(&est, drive.recording);
    const RefinementJob job = est.MakeRefinementJob(0, /*final=*/true);
    EXPECT_FALSE(job.history.t_ns.empty());
    EXPECT_TRUE(est.ApplyRefinement(job, RefineWindow(job)));
    return est.Estimate().rig.slaves[0].motion_model;
  };
  EXPECT_EQ(published_model(RigEstimatorOptions{}), MotionModel::kPlanar);
  RigEstimatorOptions general;
  general.model_selection.min_tilt_snr = 1e-3;
  general.model_selection.max_axis_std_ratio = 1e12;
  EXPECT_EQ(published_model(general), MotionModel::kGeneral);
}

TEST(RigEstimatorHistory, FinalRefinementIsTheBatchOnTheSameSets) {
  const SyntheticDrive drive = NoisyDrive(1200, 5, 1);
  RigEstimatorOptions o;
  RigEstimator est(Names(drive.recording), o);
  Feed(&est, drive.recording);
  const RefinementJob job = est.MakeRefinementJob(0, /*final=*/true);
  ASSERT_EQ(job.history.size(), drive.recording.size());
  const SlaveCalibration refined = RefineWindow(job);
  ASSERT_TRUE(est.ApplyRefinement(job, refined)) << refined.message;
  const SlaveCalibration batch = CalibrateRig(drive.recording, CalibrationOptions{}).slaves[0];
  const SlaveCalibration& online = est.Estimate().rig.slaves[0];
  ASSERT_TRUE(batch.usable()) << batch.message;
  EXPECT_TRUE(est.Estimate().online[0].flags & kFlagRefined);
  EXPECT_LT(AngleBetween(online.estimate.q, batch.estimate.q), 1e-12);
  EXPECT_LT((online.estimate.C - batch.estimate.C).norm(), 1e-12);
  EXPECT_DOUBLE_EQ(online.rot_std_deg, batch.rot_std_deg);
  EXPECT_EQ(online.pairs, batch.pairs);
  EXPECT_NE(online.message.find("converg"), std::string::npos);

  // Not due again within history_refine_period_s: no job (an unsolved start).
  const RefinementJob again = est.MakeRefinementJob(0);
  EXPECT_FALSE(again.start.solved());
}

// The batch on the whole recording finds glitches on every camera and drops their times for
// all; the history job holds the other slaves too, so a glitch of one slave leaves the same sets
// to another slave online as in the batch: the same result, bit for bit, for every slave.
TEST(RigEstimatorHistory, AnotherSlavesGlitchDropsTheSameSetsAsTheBatch) {
  SyntheticDrive drive = NoisyDrive(1200, 7, 2);
  RigRecording& rec = drive.recording;
  for (size_t k : {300u, 301u, 750u})
    rec.slaves[0].poses[k].C += Eigen::Vector3d(40.0, -25.0, 10.0);
  const RigCalibration batch = CalibrateRig(rec, CalibrationOptions{});
  ASSERT_GT(batch.slaves[1].glitches.dropped(), 0) << batch.slaves[1].message;
  RigEstimator est(Names(rec), RigEstimatorOptions{});
  Feed(&est, rec);
  for (int slave = 0; slave < 2; ++slave) {
    const RefinementJob job = est.MakeRefinementJob(slave, /*final=*/true);
    ASSERT_EQ(job.history.size(), rec.size());
    ASSERT_EQ(job.history.slaves.size(), 2u);
    EXPECT_EQ(job.history.slaves[0].name, rec.slaves[slave].name);
    const SlaveCalibration refined = RefineWindow(job);
    ASSERT_TRUE(est.ApplyRefinement(job, refined)) << refined.message;
    const SlaveCalibration& online = est.Estimate().rig.slaves[slave];
    const SlaveCalibration& expected = batch.slaves[slave];
    EXPECT_LT(AngleBetween(online.estimate.q, expected.estimate.q), 1e-12) << slave;
    EXPECT_LT((online.estimate.C - expected.estimate.C).norm(), 1e-12) << slave;
    EXPECT_DOUBLE_EQ(online.rot_std_deg, expected.rot_std_deg) << slave;
    EXPECT_EQ(online.pairs, expected.pairs) << slave;
    EXPECT_EQ(refined.glitches.dropped(), expected.glitches.dropped()) << slave;
  }
}

// A slave's pose as the rig and its odometry give it from the master's, both camera-local (pose
// 0 the identity): slave_world_from_slave = X⁻¹ · master_world_from_master · X with X the slave's
// mounting in master units, its translation then in slave units (p_master = scale R p_slave + C).
Pose SlaveFromMaster(const Pose& master, const Similarity& truth) {
  Pose mounting;
  mounting.q = truth.q;
  mounting.C = truth.C;
  Pose slave = mounting.Inverse() * master * mounting;
  slave.C /= truth.scale;
  return slave;
}

// A drive longer than the history is kept whole: consecutive sets merge into their group mean.
// The mean in the group of rigid motions keeps the rig's relation between the master's and the
// slave's poses exact (noise-free here: to rounding), whatever the motion within a group.
TEST(RigEstimatorHistory, LongerRecordingsMergeIntoMeansThatKeepTheRig) {
  DriveOptions d;
  d.num_frames = 1200;
  d.rotation_noise_deg = 0.0;
  d.position_noise = 0.0;
  const SyntheticDrive drive = GenerateDrive({"front", "left", "back"}, DemoRig(), d);
  const RigRecording& rec = drive.recording;
  for (size_t k = 0; k < rec.size(); k += 100) {  // the relation on the drive's own poses
    const Pose expected = SlaveFromMaster(rec.master.poses[k], drive.truth[0]);
    ASSERT_LT(AngleBetween(expected.q, rec.slaves[0].poses[k].q), 1e-9) << k;
    ASSERT_LT((expected.C - rec.slaves[0].poses[k].C).norm(), 1e-9) << k;
  }
  RigEstimatorOptions o;
  o.history_sets = 500;  // 1200 sets: groups of 4 sets
  RigEstimator est(Names(rec), o);
  Feed(&est, rec);
  const RefinementJob job = est.MakeRefinementJob(0, /*final=*/true);
  ASSERT_EQ(job.history.size(), 300u);
  EXPECT_EQ(job.history_stride, 4u);
  ASSERT_EQ(job.history.slaves.size(), 2u);  // the other slave's means at the same times
  double max_angle_rad = 0.0;
  double max_position = 0.0;
  double max_step_rad = 0.0;  // how far apart the poses of a group are
  for (size_t k = 0; k < job.history.size(); ++k) {
    // the mean stamp of sets 4k..4k+3, evenly spaced
    EXPECT_NEAR(static_cast<double>(job.history.t_ns[k]),
                0.5 * static_cast<double>(rec.t_ns[4 * k] + rec.t_ns[4 * k + 3]), 1.0);
    const Pose expected = SlaveFromMaster(job.history.master.poses[k], drive.truth[0]);
    max_angle_rad =
        std::max(max_angle_rad, AngleBetween(expected.q, job.history.slaves[0].poses[k].q));
    max_position = std::max(max_position, (expected.C - job.history.slaves[0].poses[k].C).norm());
    max_step_rad = std::max(max_step_rad,
                            AngleBetween(rec.master.poses[4 * k].q, rec.master.poses[4 * k + 3].q));
  }
  EXPECT_GT(max_step_rad, 1e-3);  // the groups are not trivial
  EXPECT_LT(max_angle_rad, 1e-9);
  EXPECT_LT(max_position, 1e-9);
}

// On white pose noise the group means keep the information of every set (the mean of 4 poses
// has half their noise), where keeping every 4th set would double the σ: the online estimate's
// σ is the batch's on all the sets (1.3× is the bound the online estimator is held to), and its
// error within 3σ of the truth.
TEST(RigEstimatorHistory, LongerRecordingsKeepTheBatchAccuracy) {
  double sum_rot_ratio = 0.0;
  double sum_pos_ratio = 0.0;
  const std::vector<uint64_t> seeds = {1u, 2u, 3u, 4u};
  for (const uint64_t seed : seeds) {
    const SyntheticDrive drive = NoisyDrive(1200, seed, 2);
    const RigRecording& rec = drive.recording;
    RigEstimatorOptions o;
    o.history_sets = 500;
    RigEstimator est(Names(rec), o);
    Feed(&est, rec);
    const RefinementJob job = est.MakeRefinementJob(0, /*final=*/true);
    ASSERT_EQ(job.history.size(), 300u) << seed;
    const SlaveCalibration refined = RefineWindow(job);
    ASSERT_TRUE(est.ApplyRefinement(job, refined)) << refined.message;
    EXPECT_FALSE(refined.pairs.empty());  // the batch's result, not the window's
    EXPECT_NE(refined.message.find("batch on the 300 means of 4 consecutive sets since the start"),
              std::string::npos)
        << refined.message;
    const SlaveCalibration& online = est.Estimate().rig.slaves[0];
    ASSERT_TRUE(online.usable()) << online.message;
    const SlaveCalibration all = CalibrateRig(rec, job.history_options).slaves[0];
    ASSERT_TRUE(all.solved()) << all.message;
    sum_rot_ratio += online.rot_std_deg / all.rot_std_deg;
    sum_pos_ratio += online.pos_std.norm() / all.pos_std.norm();
    const double rot_err_deg = AngleBetween(online.estimate.q, drive.truth[0].q) * kDegPerRad;
    EXPECT_LT(rot_err_deg, 3.0 * online.rot_std_deg) << seed;
    EXPECT_LT((online.estimate.C - drive.truth[0].C).norm(), 3.0 * online.pos_std.norm()) << seed;
  }
  // Each σ is estimated from its drive's residuals (±30 % from seed to seed): their mean ratio.
  const double n = static_cast<double>(seeds.size());
  EXPECT_LT(sum_rot_ratio / n, 1.3);
  EXPECT_LT(sum_pos_ratio / n, 1.3);
}

TEST(RigEstimatorHistory, HistorySetsIsChecked) {
  RigEstimatorOptions bad;
  bad.history_sets = -1;
  EXPECT_NE(bad.Check().message().find("history_sets"), std::string::npos);
}

}  // namespace
}  // namespace rigcal
