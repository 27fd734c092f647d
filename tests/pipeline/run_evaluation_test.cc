// Scoring a run's estimate against the simulated truth: a planar estimate without a prior is
// scored in the plane (its offset along the axis is unknown, not wrong), a translational one
// has no position to score, and the table says which figures were not determined.
#include "rigcal/pipeline/run_evaluation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "rigcal/calib/quaternion.h"

namespace rigcal::tools {
namespace {

SlaveEvaluation Scored(const SlaveCalibration& slave, const Similarity& truth) {
  SlaveEvaluation e;
  e.name = slave.name;
  e.usable = true;
  e.truth_master_units = truth;
  ScoreEstimate(slave, slave.estimate.scale, &e);
  return e;
}

Similarity Truth() {
  Similarity t;
  t.q = AxisAngle(Eigen::Vector3d::UnitY(), 90.0 * kRadPerDeg);
  t.C = Eigen::Vector3d(-1.0, 0.4, 2.0);  // y is the vertical (the planar axis below)
  t.scale = 0.5;
  return t;
}

TEST(RunEvaluation, PlanarEstimateWithoutPriorIsScoredInThePlane) {
  SlaveCalibration slave;
  slave.name = "left";
  slave.termination = Termination::kSolved;
  slave.state = SlaveState::kConverged;
  slave.estimate = Truth();
  slave.estimate.C.y() = 0.0;     // unknown offset, reported as 0
  slave.estimate.C.x() += 0.003;  // 3 units error in the plane
  slave.unobservable = {Eigen::Vector3d::UnitY()};
  slave.unobservable_from_prior = false;
  const SlaveEvaluation e = Scored(slave, Truth());
  EXPECT_TRUE(e.axis_unknown);
  EXPECT_NEAR(e.error.plane_err, 0.003, 1e-12);
  EXPECT_NEAR(e.error.axis_err, 0.4, 1e-12);  // what a 0 would cost, not shown as an error
  // In-plane direction error: angle between (-1, 0, 2) and (-0.997, 0, 2).
  const double expected = std::acos(
      Eigen::Vector2d(-1.0, 2.0).normalized().dot(Eigen::Vector2d(-0.997, 2.0).normalized()));
  EXPECT_NEAR(e.error.dir_deg, expected * kDegPerRad, 1e-9);
  EXPECT_NEAR(
      e.error.dist_pct,
      std::abs(std::hypot(-0.997, 2.0) - std::hypot(-1.0, 2.0)) / std::hypot(-1.0, 2.0) * 100,
      1e-9);

  RunEvaluation run;
  run.master_metres_per_unit = 1.0;
  run.slaves = {e};
  const std::string table = FormatEvaluation(run);
  EXPECT_NE(table.find("unobs"), std::string::npos) << table;
  EXPECT_NE(table.find("3.0000"), std::string::npos) << table;  // plane error, mm
  EXPECT_NE(table.find("planar motion"), std::string::npos) << table;
}

TEST(RunEvaluation, PlanarEstimateWithPriorScoresTheAxisToo) {
  SlaveCalibration slave;
  slave.termination = Termination::kSolved;
  slave.state = SlaveState::kConverged;
  slave.estimate = Truth();
  slave.estimate.C.y() = 0.41;  // from the nominal mounting
  slave.unobservable = {Eigen::Vector3d::UnitY()};
  slave.unobservable_from_prior = true;
  const SlaveEvaluation e = Scored(slave, Truth());
  EXPECT_FALSE(e.axis_unknown);
  EXPECT_NEAR(e.error.axis_err, 0.01, 1e-12);
  EXPECT_NEAR(e.error.plane_err, 0.0, 1e-12);
  RunEvaluation run;
  run.master_metres_per_unit = 2.0;
  run.slaves = {e};
  const std::string table = FormatEvaluation(run);
  EXPECT_EQ(table.find("unobs"), std::string::npos) << table;
  EXPECT_NE(table.find("20.0000"), std::string::npos) << table;  // 0.01 units of 2 m
  // The unit alignment is said, in the table and as the JSON's truth_alignment.
  EXPECT_NE(table.find("positions compared after aligning the master unit to the truth: 1 master "
                       "unit = 2 m"),
            std::string::npos)
      << table;
  const TruthAlignment alignment = AlignmentOf(run);
  EXPECT_TRUE(alignment.applied);
  EXPECT_EQ(alignment.metres_per_unit, 2.0);
}

TEST(RunEvaluation, TranslationalEstimateHasNoPositionToScore) {
  SlaveCalibration slave;
  slave.termination = Termination::kSolved;
  slave.state = SlaveState::kConverged;
  slave.estimate = Truth();
  slave.estimate.C.setZero();
  slave.position_observable = false;
  slave.unobservable = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(),
                        Eigen::Vector3d::UnitZ()};
  const SlaveEvaluation e = Scored(slave, Truth());
  EXPECT_FALSE(e.position_observable);
  EXPECT_NEAR(e.error.rot_deg, 0.0, 1e-9);
  RunEvaluation run;
  run.master_metres_per_unit = 1.0;
  run.slaves = {e};
  const std::string table = FormatEvaluation(run);
  EXPECT_EQ(table.find("100.0000"), std::string::npos) << table;  // no made-up distance error
  EXPECT_NE(table.find("unobs"), std::string::npos) << table;
}

}  // namespace
}  // namespace rigcal::tools
