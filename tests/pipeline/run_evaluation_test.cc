// SPDX-License-Identifier: Apache-2.0
// Scoring a run's estimate against the simulated truth: a planar estimate without a prior is
// scored in the plane (its offset along the axis is unknown, not wrong), a translational one
// has no position to score, and the table says which figures were not determined; the master
// unit is the unit of the master segment the estimate is in.
#include "rigcal/pipeline/run_evaluation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "pipeline/room_rig_spec.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::pipeline {
namespace {

SlaveEvaluation Scored(const SlaveCalibration& slave, const Similarity& truth) {
  SlaveEvaluation e;
  e.name = slave.name;
  e.usable = true;
  e.truth_master_units = truth;
  io::ScoreSlave(slave, &e);
  return e;
}

// A run whose master unit is `metres_per_unit` m.
RunEvaluation Metric(double metres_per_unit, const SlaveEvaluation& e) {
  RunEvaluation run;
  run.master_metres_per_unit = metres_per_unit;
  run.alignment.applied = true;
  run.alignment.metres_per_unit = metres_per_unit;
  run.alignment.message =
      "1 master unit = " + std::to_string(static_cast<int>(metres_per_unit)) + " m";
  run.slaves = {e};
  return run;
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

  const std::string table = FormatEvaluation(Metric(1.0, e));
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
  const RunEvaluation run = Metric(2.0, e);
  const std::string table = FormatEvaluation(run);
  EXPECT_EQ(table.find("unobs"), std::string::npos) << table;
  EXPECT_NE(table.find("20.0000"), std::string::npos) << table;  // 0.01 units of 2 m
  // The unit alignment is said, in the table and as the JSON's truth_alignment.
  EXPECT_NE(table.find("1 master unit = 2 m"), std::string::npos) << table;
  const io::TruthAlignment alignment = AlignmentOf(run);
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
  const std::string table = FormatEvaluation(Metric(1.0, e));
  EXPECT_EQ(table.find("100.0000"), std::string::npos) << table;  // no made-up distance error
  EXPECT_NE(table.find("unobs"), std::string::npos) << table;
}

// A VO's origin is where it initialised, not necessarily its first pose written (frames before
// it initialised, a pose dropped): each camera's unit is fitted to positions relative to its
// first pose on both sides. Fitted to the raw VO positions, with the origin 10 frames before the
// first pose, the units here came out 24-25 % small (device/loopback_run's scale truth 5 %).
TEST(RunEvaluation, UnitsDoNotDependOnWhereTheOdometryStarted) {
  auto rig = sim::MakeSimulatedRig(RoomRigSpec(4.0));
  ASSERT_TRUE(rig) << rig.error();
  const std::vector<double> units_per_metre = {2.5, 0.8, 1.3};
  const int origin_frame = 10;
  std::vector<std::vector<CameraPose>> poses(units_per_metre.size());
  for (int camera = 0; camera < static_cast<int>(units_per_metre.size()); ++camera) {
    const auto time_s = [&](int k) {
      return 1e-9 * static_cast<double>(rig->FrameTimeNs(k) - rig->epoch_ns());
    };
    const Pose origin = rig->WorldFromCameraAt(camera, time_s(origin_frame));
    for (int k = origin_frame + 10; k < rig->num_frames(); k += 2) {
      CameraPose p;
      p.camera = camera;
      p.t_ns = rig->FrameTimeNs(k);
      p.pose = origin.Between(rig->WorldFromCameraAt(camera, time_s(k)));
      p.pose.C *= units_per_metre[static_cast<size_t>(camera)];
      poses[static_cast<size_t>(camera)].push_back(p);
    }
  }
  RigCalibration result;
  result.slaves.emplace_back().name = "side";
  result.slaves.emplace_back().name = "up";
  auto evaluation = EvaluateRun(*rig, poses, result);
  ASSERT_TRUE(evaluation.ok()) << evaluation.error();
  for (size_t camera = 0; camera < units_per_metre.size(); ++camera) {
    const SegmentUnit& unit = evaluation->units[camera].at(0);
    EXPECT_NEAR(unit.metres_per_unit, 1.0 / units_per_metre[camera], 1e-9) << "camera " << camera;
    EXPECT_LT(unit.fit_rms_m, 1e-9) << "camera " << camera;
    if (camera > 0) {
      EXPECT_NEAR(evaluation->slaves.at(camera - 1).truth_master_units.scale,
                  units_per_metre[0] / units_per_metre[camera], 1e-9);
    }
  }
}

}  // namespace
}  // namespace rigcal::pipeline
