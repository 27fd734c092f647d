// SPDX-License-Identifier: Apache-2.0
// Matching the trajectories of several cameras by time stamp: tolerance, different rates, and
// the errors that name ranges and slaves.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "io/trajectory_fixtures.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::io::trajectory_test {
namespace {

std::vector<int64_t> Stamps(int64_t start, int64_t step, int count) {
  std::vector<int64_t> t;
  for (int k = 0; k < count; ++k) t.push_back(start + step * k);
  return t;
}

TEST(MatchTrajectoriesTest, SameStampsMatchEverything) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto slave = MakeTrajectory("s", Stamps(0, 50'000'000, 10));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  EXPECT_TRUE(rec->Check().ok()) << rec->Check().message();
  EXPECT_EQ(rec->t_ns, master.t_ns);
  EXPECT_EQ(rec->master.name, "m");
  ASSERT_EQ(rec->slaves.size(), 1u);
  EXPECT_EQ(rec->slaves[0].name, "s");
  EXPECT_EQ(rec->slaves[0].segment, slave.segment);
}

TEST(MatchTrajectoriesTest, OffsetWithinToleranceAndKeepsOnlyStampsInAllSlaves) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto early = MakeTrajectory("early", Stamps(-3'000'000, 50'000'000, 10));
  auto gappy = MakeTrajectory("gappy", Stamps(1'000'000, 50'000'000, 10));
  // Remove master stamp 4's partner from the second slave.
  gappy.t_ns.erase(gappy.t_ns.begin() + 4);
  gappy.poses.erase(gappy.poses.begin() + 4);
  gappy.segment.erase(gappy.segment.begin() + 4);
  const auto rec = MatchTrajectories(master, {early, gappy}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  ASSERT_EQ(rec->size(), 9u);
  EXPECT_EQ(rec->t_ns[4], master.t_ns[5]);
  // Poses travel with their stamps (after the erase, gappy's index 4 is stamped 251 ms).
  EXPECT_EQ(rec->slaves[1].poses[4].C, gappy.poses[4].C);
  EXPECT_EQ(rec->slaves[0].poses[4].C, early.poses[5].C);
  EXPECT_EQ(rec->master.poses[4].C, master.poses[5].C);
}

TEST(MatchTrajectoriesTest, OffsetBeyondToleranceMatchesNothing) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto late = MakeTrajectory("late", Stamps(7'000'000, 50'000'000, 10));
  const auto rec = MatchTrajectories(master, {late}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("late matched 0 of 10"));
}

TEST(MatchTrajectoriesTest, FastMasterUsesEverySlavePoseOnce) {
  // Master at 200 Hz, slave at 20 Hz: within 5 ms up to two master stamps are near one slave
  // stamp; only the mutually nearest pair is kept.
  const auto master = MakeTrajectory("m", Stamps(0, 5'000'000, 200));
  const auto slave = MakeTrajectory("s", Stamps(2'000'000, 50'000'000, 20));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  ASSERT_EQ(rec->size(), 20u);
  for (size_t k = 0; k < rec->size(); ++k) {
    EXPECT_EQ(rec->t_ns[k], static_cast<int64_t>(k) * 50'000'000) << k;
    EXPECT_EQ(rec->slaves[0].poses[k].C, slave.poses[k].C) << k;
  }
}

TEST(MatchTrajectoriesTest, SlowMasterTakesNearestSlavePose) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 20));
  const auto slave = MakeTrajectory("s", Stamps(-1'000'000, 5'000'000, 200));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_TRUE(rec.ok()) << rec.error();
  ASSERT_EQ(rec->size(), 20u);
  // Around master stamp k, slave index 10 k is 1 ms early and 10 k + 1 is 4 ms late.
  for (size_t k = 0; k < rec->size(); ++k) {
    EXPECT_EQ(rec->slaves[0].poses[k].C, slave.poses[10 * k].C) << k;
  }
}

TEST(MatchTrajectoriesTest, NoOverlapNamesRanges) {
  const auto master = MakeTrajectory("master_cam", Stamps(0, 1'000'000'000, 10));
  const auto slave = MakeTrajectory("cam1", Stamps(100'000'000'000, 1'000'000'000, 10));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("no overlapping time range: master master_cam 0.000..9.000 s, "
                                     "cam1 100.000..109.000 s"));
}

TEST(MatchTrajectoriesTest, FewerThanTwoMatchesNamesTheSlave) {
  const auto master = MakeTrajectory("m", Stamps(0, 50'000'000, 10));
  const auto good = MakeTrajectory("good", Stamps(0, 50'000'000, 10));
  const auto one = MakeTrajectory("one", {450'000'000, 460'000'000});
  const auto rec = MatchTrajectories(master, {good, one}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("only 1 master stamps"));
  EXPECT_THAT(rec.error(), HasSubstr("good matched 10 of 10"));
  EXPECT_THAT(rec.error(), HasSubstr("one matched 1 of 10"));
}

TEST(MatchTrajectoriesTest, DuplicateNamesAreRejected) {
  const auto master = MakeTrajectory("cam", Stamps(0, 50'000'000, 10));
  const auto slave = MakeTrajectory("cam", Stamps(0, 50'000'000, 10));
  const auto rec = MatchTrajectories(master, {slave}, 5'000'000);
  ASSERT_FALSE(rec.ok());
  EXPECT_THAT(rec.error(), HasSubstr("two cameras are named 'cam'"));
}
}  // namespace
}  // namespace rigcal::io::trajectory_test
