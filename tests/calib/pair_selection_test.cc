// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/pair_selection.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal {
namespace {

RigRecording Drive(int frames) {
  DriveOptions opt;
  opt.num_frames = frames;
  return GenerateDrive({"m", "s1", "s2"}, DemoRig(), opt).recording;
}

TEST(PairSelection, SinceStartAndRelative) {
  const RigRecording rec = Drive(50);
  const auto start = SelectPairs(rec, {.policy = PairOptions::Policy::kSinceStart});
  ASSERT_EQ(start.size(), 49u);
  EXPECT_EQ(start.front().a, 0);
  EXPECT_EQ(start.back().b, 49);
  const auto rel = SelectPairs(rec, {.policy = PairOptions::Policy::kRelative, .step = 5});
  ASSERT_EQ(rel.size(), 45u);
  for (const auto& p : rel) EXPECT_EQ(p.b - p.a, 5);
}

TEST(PairSelection, AutoReachesTargetWithinSpan) {
  const RigRecording rec = Drive(1000);
  PairOptions opt;  // auto, with a target the demo drive (35 deg amplitude) reaches
  opt.target_angle_deg = 30.0;
  const auto pairs = SelectPairs(rec, opt);
  ASSERT_GT(pairs.size(), 500u);
  const int span = AutoPairSpan(rec, opt);
  ASSERT_GT(span, 0);
  const int max_span = std::min(static_cast<int>(opt.max_span_fraction * rec.size()), 2 * span);
  int reached = 0;
  for (const auto& p : pairs) {
    ASSERT_LT(p.a, p.b);
    ASSERT_LE(p.b - p.a, max_span);
    const double angle = AngleBetween(rec.master.poses[p.a].q, rec.master.poses[p.b].q);
    if (angle * kDegPerRad >= opt.target_angle_deg) ++reached;
    // The pair is the first b reaching a target: b - 1 must not have reached both.
    if (p.b - p.a > 1) {
      const double prev = AngleBetween(rec.master.poses[p.a].q, rec.master.poses[p.b - 1].q);
      EXPECT_LT(prev * kDegPerRad, opt.target_angle_deg);
    }
  }
  EXPECT_GT(reached, 0);
}

// With a limit on the pairs per end pose, walks stopping at a taken end move on to the next
// free pose (or the anchor is dropped): no pose ends more pairs than the limit.
TEST(PairSelection, LimitOfPairsPerEndPose) {
  const RigRecording rec = Drive(1000);
  PairOptions opt;
  opt.target_angle_deg = 30.0;
  std::map<int, int> unlimited_ends;
  for (const auto& p : SelectPairs(rec, opt)) ++unlimited_ends[p.b];
  int most = 0;
  for (const auto& [b, uses] : unlimited_ends) most = std::max(most, uses);
  ASSERT_GT(most, 1);  // the default shares ends on this drive
  for (int limit : {1, 2}) {
    opt.max_pairs_per_end = limit;
    std::map<int, int> ends;
    const auto pairs = SelectPairs(rec, opt);
    ASSERT_GT(pairs.size(), 300u);
    for (const auto& p : pairs) {
      ++ends[p.b];
      const double angle = AngleBetween(rec.master.poses[p.a].q, rec.master.poses[p.b].q);
      const double trans = (rec.master.poses[p.b].C - rec.master.poses[p.a].C).norm();
      EXPECT_TRUE(angle * kDegPerRad >= opt.min_angle_deg || trans > 0.0);
    }
    for (const auto& [b, uses] : ends) EXPECT_LE(uses, limit) << "pose " << b;
  }
  opt.max_pairs_per_end = -1;
  const Status status = opt.Check();
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind("max_pairs_per_end: ", 0), 0u) << status.message();
}

// White pose noise: longer spans only add signal, so the best span is long. Random-walk drift
// makes the noise grow with the span, so the best span is shorter.
TEST(PairSelection, AutoSpanFollowsNoiseKind) {
  DriveOptions white;
  white.num_frames = 2000;
  white.rotation_noise_deg = 0.2;
  white.position_noise = 0.0;
  DriveOptions drift = white;
  drift.rotation_noise_deg = 0.01;
  drift.drift_deg_per_frame = 0.05;
  const auto rec_white = GenerateDrive({"m", "s"}, {DemoRig()[0]}, white).recording;
  const auto rec_drift = GenerateDrive({"m", "s"}, {DemoRig()[0]}, drift).recording;
  const int span_white = AutoPairSpan(rec_white, PairOptions{});
  const int span_drift = AutoPairSpan(rec_drift, PairOptions{});
  EXPECT_GE(span_white, 128);
  EXPECT_LT(span_drift, span_white);
  // No rotation: 0, the walk goes by translation.
  DriveOptions still = white;
  still.motion = DriveOptions::Motion::kTranslationOnly;
  still.rotation_noise_deg = 0.0;
  EXPECT_EQ(AutoPairSpan(GenerateDrive({"m", "s"}, {DemoRig()[0]}, still).recording, {}), 0);
}

TEST(PairSelection, NeverCrossesSegments) {
  RigRecording rec = Drive(300);
  for (size_t k = 150; k < rec.size(); ++k) rec.master.segment[k] = 1;
  for (size_t k = 100; k < rec.size(); ++k) rec.slaves[0].segment[k] = 4;
  for (auto policy : {PairOptions::Policy::kAuto, PairOptions::Policy::kRelative,
                      PairOptions::Policy::kSinceStart}) {
    PairOptions opt;
    opt.policy = policy;
    opt.step = 20;
    const auto pairs = SelectPairs(rec, opt);
    ASSERT_FALSE(pairs.empty());
    for (const auto& p : pairs) EXPECT_EQ(rec.master.segment[p.a], rec.master.segment[p.b]);
    for (const auto& m : MotionsForSlave(rec, 0, pairs)) {
      EXPECT_TRUE((m.t_a_ns < rec.t_ns[100]) == (m.t_b_ns < rec.t_ns[100]));
    }
  }
}

TEST(PairSelection, OptionsCheckNamesField) {
  PairOptions opt;
  EXPECT_TRUE(opt.Check().ok()) << opt.Check().message();
  opt.max_span_fraction = 0.0;
  const Status status = opt.Check();
  EXPECT_FALSE(status.ok());
  EXPECT_EQ(status.message().rfind("max_span_fraction: ", 0), 0u) << status.message();
}

}  // namespace
}  // namespace rigcal
