// SPDX-License-Identifier: Apache-2.0
// Cancelling a refinement (CalibrationOptions::cancel, OnlineCalibrator::CancelRefinements), for
// a stop by a signal that comes during a history refinement: a cancelled batch solve returns
// early and unsolved; a flag that is never set changes nothing (bit for bit); the periodic
// refinements after a cancel are left out, the final one still runs in full; a lossless push
// that waits for the estimator cancels them when the caller's stop flag is set
// (CancelRefinementsWhen).
#include <gtest/gtest.h>

#include <atomic>

#include "rigcal/calib/online_calibrator.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

const std::vector<std::string> kNames = {"front", "left", "back"};

RigRecording Recording(int frames) {
  DriveOptions d;
  d.num_frames = frames;
  return GenerateDrive(kNames, DemoRig(), d).recording;
}

CalibrationOptions GlsOptions() {
  CalibrationOptions options;
  options.pairs.policy = PairOptions::Policy::kGls;
  return options;
}

TEST(RefinementCancel, ASetFlagEndsTheBatchSolveUnsolved) {
  const RigRecording rec = Recording(400);
  const std::atomic<bool> cancel{true};
  CalibrationOptions options = GlsOptions();
  options.cancel = &cancel;
  const RigCalibration r = CalibrateRig(rec, options);
  ASSERT_EQ(r.slaves.size(), 2U);
  for (const SlaveCalibration& slave : r.slaves) {
    EXPECT_FALSE(slave.solved()) << slave.name;
    EXPECT_NE(slave.message.find("cancelled"), std::string::npos) << slave.message;
  }
}

TEST(RefinementCancel, AFlagNeverSetChangesNothing) {
  const RigRecording rec = Recording(400);
  const RigCalibration plain = CalibrateRig(rec, GlsOptions());
  const std::atomic<bool> cancel{false};
  CalibrationOptions options = GlsOptions();
  options.cancel = &cancel;
  const RigCalibration watched = CalibrateRig(rec, options);
  ASSERT_EQ(plain.slaves.size(), watched.slaves.size());
  for (size_t i = 0; i < plain.slaves.size(); ++i) {
    const SlaveCalibration& a = plain.slaves[i];
    const SlaveCalibration& b = watched.slaves[i];
    ASSERT_TRUE(a.solved()) << a.message;
    EXPECT_EQ(a.estimate.q.coeffs(), b.estimate.q.coeffs());
    EXPECT_EQ(a.estimate.C, b.estimate.C);
    EXPECT_EQ(a.rot_std_deg, b.rot_std_deg);
    EXPECT_EQ(a.pos_std, b.pos_std);
    EXPECT_EQ(a.message, b.message);
  }
}

// Lossless on stream time (the same pushes, the same refinements): a history refinement every
// 2 s of stream time.
OnlineOptions FrequentHistoryRefinements() {
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.refine_period_s = 1.0;
  options.estimator.history_refine_period_s = 2.0;
  return options;
}

TEST(RefinementCancel, AfterACancelOnlyTheFinalRefinementRuns) {
  const RigRecording rec = Recording(600);
  OnlineCalibrator calibrator(kNames, FrequentHistoryRefinements());
  calibrator.Start();
  const size_t half = rec.size() / 2;
  for (size_t k = 0; k < half; ++k) {
    for (int cam = 0; cam < 3; ++cam) calibrator.Push(rec.PoseAt(cam, k));
  }
  calibrator.Drain();
  const int applied_before = calibrator.refinements_applied();
  ASSERT_GT(applied_before, 0) << "no periodic refinement in the first half";
  calibrator.CancelRefinements();
  const OnlineCalibrator::RefinementPasses passes_before = calibrator.refinement_passes();
  for (size_t k = half; k < rec.size(); ++k) {
    for (int cam = 0; cam < 3; ++cam) calibrator.Push(rec.PoseAt(cam, k));
  }
  calibrator.Flush();
  // Left out: no pass began, none applied.
  EXPECT_EQ(calibrator.refinement_passes().begun, passes_before.begun);
  EXPECT_EQ(calibrator.refinements_applied(), applied_before);
  calibrator.RefineNow(/*final=*/true);
  calibrator.Stop();
  const OnlineCalibrator::RefinementPasses passes = calibrator.refinement_passes();
  EXPECT_EQ(passes.begun, passes_before.begun + 1);
  EXPECT_EQ(passes.ended, passes.begun);
  EXPECT_GT(calibrator.refinements_applied(), applied_before);
  const SlaveCalibration final = calibrator.Estimate().rig.slaves.at(0);
  EXPECT_TRUE(final.usable()) << final.message;
  EXPECT_FALSE(final.pairs.empty()) << "the final refinement is not the history's";
}

// A lossless push that waits for room while the estimator thread refines, with the caller's
// stop flag (CancelRefinementsWhen) set: the periodic refinements are cancelled (the one in flight ends early), so no
// pass begins after the first wait that saw the stop, and the pushes and the flush end.
TEST(RefinementCancel, AStopSeenByAWaitingPushCancelsThePeriodicRefinements) {
  const RigRecording rec = Recording(1200);
  OnlineCalibrator calibrator(kNames, FrequentHistoryRefinements());
  calibrator.Start();
  std::atomic<bool> stop{false};
  calibrator.CancelRefinementsWhen(&stop);
  size_t k = 0;
  // Until the estimator has refined a few times (a history of a few hundred sets).
  for (; k < rec.size() && calibrator.refinements_applied() < 4; ++k) {
    for (int cam = 0; cam < 3; ++cam) calibrator.Push(rec.PoseAt(cam, k));
  }
  ASSERT_LT(k, rec.size() / 2) << "fewer than 4 refinements on half the drive";
  stop.store(true);
  // A push waits for the estimator within a few sets (a history refinement every 40 sets).
  const size_t stopped_at = k;
  for (; k < stopped_at + 100; ++k) {
    for (int cam = 0; cam < 3; ++cam) calibrator.Push(rec.PoseAt(cam, k));
  }
  calibrator.Drain();  // the pass in flight, cancelled, has ended
  const OnlineCalibrator::RefinementPasses cancelled = calibrator.refinement_passes();
  EXPECT_EQ(cancelled.ended, cancelled.begun);
  for (; k < rec.size(); ++k) {
    for (int cam = 0; cam < 3; ++cam) calibrator.Push(rec.PoseAt(cam, k));
  }
  calibrator.Flush();
  const OnlineCalibrator::RefinementPasses after = calibrator.refinement_passes();
  EXPECT_EQ(after.begun, cancelled.begun)
      << "periodic passes began after the stop (a history refinement is due every 40 sets)";
  calibrator.Stop();
}

}  // namespace
}  // namespace rigcal
