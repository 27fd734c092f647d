// SPDX-License-Identifier: Apache-2.0
// OnlineCalibrator::RefineFinalBefore, the end of a stream stopped by a signal: the final history
// refinement when the last one's duration says it ends in time (the result of RefineNow(true)
// bit for bit), else, or when no history refinement was timed yet, the window's refinement.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "rigcal/calib/online_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

const std::vector<std::string> kNames = {"front", "left", "back"};
using Clock = std::chrono::steady_clock;

RigRecording Recording() {
  DriveOptions d;
  d.num_frames = 600;
  return GenerateDrive(kNames, DemoRig(), d).recording;
}

// Lossless on stream time: the same pushes give the same estimate bit for bit. One history
// refinement (the first, due at history_min_sets) and none after until the final one.
OnlineOptions OneHistoryRefinement() {
  OnlineOptions options;
  options.lossless = true;
  options.refine_on_stream_time = true;
  options.refine_period_s = 1.0;
  options.estimator.history_refine_period_s = 1e6;
  return options;
}

enum class Final { kNone, kRefineNow, kBefore };
struct Outcome {
  SlaveCalibration flushed;  // before the final refinement
  SlaveCalibration final;
};

Outcome Calibrate(const RigRecording& rec, const OnlineOptions& options, Final how,
                  Clock::duration budget = {}) {
  OnlineCalibrator calibrator(kNames, options);
  calibrator.Start();
  for (size_t k = 0; k < rec.size(); ++k) {
    for (int cam = 0; cam < 3; ++cam) calibrator.Push(rec.PoseAt(cam, k));
  }
  calibrator.Flush();
  Outcome out;
  out.flushed = calibrator.Estimate().rig.slaves.at(0);
  if (how == Final::kRefineNow) calibrator.RefineNow(/*final=*/true);
  if (how == Final::kBefore) calibrator.RefineFinalBefore(Clock::now() + budget);
  calibrator.Stop();
  out.final = calibrator.Estimate().rig.slaves.at(0);
  return out;
}

void ExpectSame(const SlaveCalibration& a, const SlaveCalibration& b) {
  EXPECT_EQ(a.estimate.q.coeffs(), b.estimate.q.coeffs());
  EXPECT_EQ(a.estimate.C, b.estimate.C);
  EXPECT_EQ(a.estimate.scale, b.estimate.scale);
  EXPECT_EQ(a.rot_std_deg, b.rot_std_deg);
}

TEST(OnlineFinalRefinement, InTimeItIsTheFinalHistoryRefinement) {
  const RigRecording rec = Recording();
  const Outcome full = Calibrate(rec, OneHistoryRefinement(), Final::kRefineNow);
  ASSERT_TRUE(full.final.usable()) << full.final.message;
  ASSERT_FALSE(full.final.pairs.empty()) << "the final refinement is not the history's";
  // The history's result at history_min_sets is not the final one on 600 sets.
  ASSERT_NE(full.flushed.estimate.q.coeffs(), full.final.estimate.q.coeffs());
  const Outcome before =
      Calibrate(rec, OneHistoryRefinement(), Final::kBefore, std::chrono::hours(1));
  ExpectSame(before.final, full.final);
}

// The window's refinement: not the history's (no pairs named), not the estimate before it.
void ExpectWindowRefined(const Outcome& run) {
  ASSERT_TRUE(run.final.usable()) << run.final.message;
  EXPECT_TRUE(run.final.pairs.empty()) << "the history refinement ran";
  EXPECT_NE(run.final.estimate.q.coeffs(), run.flushed.estimate.q.coeffs())
      << "the window was not refined";
  EXPECT_TRUE(std::isfinite(run.final.scales.back().std)) << "the scale's σ is unknown";
}

TEST(OnlineFinalRefinement, TooLateTheWindowIsRefined) {
  ExpectWindowRefined(
      Calibrate(Recording(), OneHistoryRefinement(), Final::kBefore, -std::chrono::seconds(1)));
}

TEST(OnlineFinalRefinement, NoneTimedTheWindowIsRefined) {
  const RigRecording rec = Recording();
  OnlineOptions options = OneHistoryRefinement();
  options.refine_period_s = 0.0;  // no background refinement: none timed
  const Outcome full = Calibrate(rec, options, Final::kRefineNow);
  ASSERT_FALSE(full.final.pairs.empty()) << "the final refinement is not the history's";
  ExpectWindowRefined(Calibrate(rec, options, Final::kBefore, std::chrono::hours(1)));
}

}  // namespace
}  // namespace rigcal
