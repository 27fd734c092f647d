// SPDX-License-Identifier: Apache-2.0
// The JSON schema shared by the commands, the text table, the Euler angle and axis-angle
// helpers (continuous through gimbal lock) and the truth's unit alignment in both views.
#include "rigcal/io/result_json.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>
#include <set>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"

namespace rigcal::io {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

Similarity MakeRig(const Eigen::Vector3d& axis, double angle_deg, const Eigen::Vector3d& c,
                   double scale) {
  Similarity s;
  s.q = AxisAngle(axis, angle_deg * kRadPerDeg);
  s.C = c;
  s.scale = scale;
  return s;
}

struct Fixture {
  RigCalibration result;
  std::map<std::string, Similarity> truth;
};

// left: converged, one scale; back: three segment scales; still: insufficient motion.
Fixture MakeFixture() {
  Fixture f;
  RigCalibration& r = f.result;
  r.master = "front";
  r.pairs_selected = 200;
  SlaveCalibration left;
  left.name = "left";
  left.estimate = MakeRig({0, 1, 0}, -89.5, {-0.84, 0.05, -0.61}, 0.505);
  left.scales = {SegmentScale{0, 0.505, 0.002}};
  left.rot_std_deg = 0.02;
  left.pos_std = {0.001, 0.002, 0.003};
  left.motions.total = 200;
  left.motions.used = 190;
  left.motions.small_rotation = 7;
  left.motions.residual_outlier = 3;
  left.glitches.position_jump = 2;
  left.glitches.angle_mismatch = 1;
  left.glitches.in_master = 1;
  left.glitches.in_slave = 2;
  left.motion_model = MotionModel::kGeneral;
  left.scale_model = ScaleModel::kFixed;
  left.termination = Termination::kSolved;
  left.state = SlaveState::kConverged;
  left.message = "converged after 7 iterations";
  SlaveCalibration back;
  back.name = "back";
  back.estimate = MakeRig({0, 1, 0}, 180, {0.1, -0.1, -2.2}, 2.0);
  back.scales = {SegmentScale{0, 2.0, 0.01}, SegmentScale{3, 2.5, 0.02}};
  back.motion_model = MotionModel::kTranslational;
  back.scale_model = ScaleModel::kSegments;
  back.unobservable = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitZ()};
  back.termination = Termination::kSolved;
  back.state = SlaveState::kConverged;
  SlaveCalibration road;  // planar: C along the vertical unknown
  road.name = "road";
  road.estimate = MakeRig({0, 1, 0}, 90, {0.9, 0.0, -1.5}, 2.0);
  road.scales = {SegmentScale{0, 2.0, 0.001}};
  road.rot_std_deg = 0.003;
  road.pos_std = {0.002, 0.0, 0.002};
  road.motion_model = MotionModel::kPlanar;
  road.unobservable = {Eigen::Vector3d::UnitY()};
  road.observability.planar = true;
  road.observability.planar_axis = Eigen::Vector3d::UnitY();
  road.observability.rotation_eigenvalues = Eigen::Vector4d(1e-8, 2e-8, 3.0, 4.0);
  road.observability.tilt_snr = 1.05;
  road.observability.axis_std_ratio = std::numeric_limits<double>::infinity();
  road.termination = Termination::kSolved;
  road.state = SlaveState::kConverged;
  road.message = "planar motion: C along the rotation axis is unobservable";
  SlaveCalibration still;
  still.name = "still";
  still.termination = Termination::kInsufficientMotion;
  still.message = "need >= 2 motions with rotation >= 2 deg, got 1";
  r.slaves = {left, back, still, road};
  f.truth = {{"left", MakeRig({0, 1, 0}, -90, {-0.85, 0.05, -0.6}, 0.5)},
             {"back", MakeRig({0, 1, 0}, 180, {0.1, -0.1, -2.2}, 2.0)},
             {"still", MakeRig({1, 0, 0}, 10, {1, 1, 1}, 1.0)},
             {"road", MakeRig({0, 1, 0}, 90.1, {0.9, 0.3, -1.5}, 2.0)}};
  return f;
}

std::set<std::string> Keys(const nlohmann::json& j) {
  std::set<std::string> keys;
  for (const auto& [key, value] : j.items()) keys.insert(key);
  return keys;
}

const std::set<std::string> kCommonKeys = {"name",
                                           "q_wxyz",
                                           "roll_pitch_yaw_deg",
                                           "axis_angle",
                                           "C",
                                           "std",
                                           "motions_used",
                                           "motions_rejected",
                                           "glitches",
                                           "models",
                                           "state",
                                           "termination",
                                           "message",
                                           "unobservable",
                                           "unobservable_from_prior",
                                           "observability"};

std::set<std::string> With(std::set<std::string> keys, std::initializer_list<const char*> more) {
  for (const char* k : more) keys.insert(k);
  return keys;
}

TEST(ResultJsonTest, ExactSchemaWithTruth) {
  const Fixture f = MakeFixture();
  const nlohmann::json j = ResultToJson(f.result, &f.truth);
  EXPECT_EQ(Keys(j), std::set<std::string>({"master", "slaves"}));
  EXPECT_EQ(j.at("master"), "front");
  ASSERT_TRUE(j.at("slaves").is_array());
  ASSERT_EQ(j.at("slaves").size(), 4u);
  const nlohmann::json& left = j.at("slaves")[0];
  const nlohmann::json& back = j.at("slaves")[1];
  const nlohmann::json& still = j.at("slaves")[2];
  // One scale -> "scale"; several -> "scales"; "errors" only for usable slaves with truth.
  EXPECT_EQ(Keys(left), With(kCommonKeys, {"scale", "errors"}));
  EXPECT_EQ(Keys(back), With(kCommonKeys, {"scales", "errors"}));
  EXPECT_EQ(Keys(still), With(kCommonKeys, {"scale"}));

  EXPECT_EQ(left.at("name"), "left");
  const Eigen::Quaterniond& q = f.result.slaves[0].estimate.q;
  EXPECT_EQ(left.at("q_wxyz"), nlohmann::json({q.w(), q.x(), q.y(), q.z()}));
  EXPECT_EQ(left["C"], nlohmann::json({-0.84, 0.05, -0.61}));
  EXPECT_EQ(left.at("scale"), 0.505);
  // σ along the mean axis: not computed here (NaN) -> null.
  EXPECT_EQ(left.at("std"), nlohmann::json({{"rot_deg", 0.02},
                                            {"pos", {0.001, 0.002, 0.003}},
                                            {"axis", nullptr},
                                            {"scale", 0.002}}));
  EXPECT_EQ(left.at("motions_used"), 190);
  EXPECT_EQ(left.at("motions_rejected"), 10);
  EXPECT_EQ(left.at("glitches"), nlohmann::json({{"dropped", 3},
                                                 {"position_jump", 2},
                                                 {"rotation_jump", 0},
                                                 {"angle_mismatch", 1},
                                                 {"in_master", 1},
                                                 {"in_slave", 2}}));
  EXPECT_EQ(left.at("models"), nlohmann::json({{"motion", "general"}, {"scale", "fixed"}}));
  EXPECT_EQ(left.at("termination"), "solved");
  EXPECT_EQ(left.at("state"), "converged");
  EXPECT_EQ(left.at("message"), "converged after 7 iterations");
  EXPECT_EQ(left.at("unobservable"), nlohmann::json::array());

  const CalibrationError e = CompareToTruth(f.result.slaves[0].estimate, f.truth.at("left"));
  EXPECT_EQ(Keys(left.at("errors")),
            std::set<std::string>({"rot_deg", "dir_deg", "dist_pct", "trans_err", "scale_pct",
                                   "plane_err", "axis_err"}));
  EXPECT_TRUE(left.at("errors").at("axis_err").is_null());  // no mean axis
  EXPECT_DOUBLE_EQ(left.at("errors").at("rot_deg").get<double>(), e.rot_deg);
  EXPECT_DOUBLE_EQ(left.at("errors").at("dir_deg").get<double>(), e.dir_deg);
  EXPECT_DOUBLE_EQ(left.at("errors").at("dist_pct").get<double>(), e.dist_pct);
  EXPECT_DOUBLE_EQ(left.at("errors").at("trans_err").get<double>(), e.trans_err);
  EXPECT_DOUBLE_EQ(left.at("errors").at("scale_pct").get<double>(), e.scale_pct);
  // Sanity of the error model on this fixture: 0.5 deg rotation error, 1 % scale error.
  EXPECT_NEAR(left.at("errors").at("rot_deg").get<double>(), 0.5, 1e-9);
  EXPECT_NEAR(left.at("errors").at("scale_pct").get<double>(), 1.0, 1e-9);

  ASSERT_EQ(back.at("scales").size(), 2u);
  EXPECT_EQ(back.at("scales")[1], nlohmann::json({{"segment", 3}, {"scale", 2.5}, {"std", 0.02}}));
  EXPECT_EQ(back.at("models"),
            nlohmann::json({{"motion", "translational"}, {"scale", "segments"}}));
  EXPECT_EQ(back.at("unobservable"), nlohmann::json({{1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}}));

  EXPECT_EQ(left.at("unobservable_from_prior"), false);
  EXPECT_EQ(Keys(left.at("observability")),
            std::set<std::string>({"rotation_eigenvalues", "rotation_weak_std_deg",
                                   "position_min_eigenvalue", "axis_spread_deg",
                                   "slave_axis_spread_deg", "tilt_snr", "axis_std_ratio",
                                   "max_rotation_deg", "planar", "mean_axis"}));

  // Planar: the vertical is listed, not from a prior, its σ unknown (null), and the errors are
  // split at the axis: 0.3 m along it (the unknown height, reported as 0), none in the plane.
  const nlohmann::json& road = j.at("slaves")[3];
  EXPECT_EQ(road.at("models").at("motion"), "planar");
  EXPECT_EQ(road.at("unobservable"), nlohmann::json({{0.0, 1.0, 0.0}}));
  EXPECT_EQ(road.at("unobservable_from_prior"), false);
  EXPECT_TRUE(road.at("std").at("axis").is_null());
  EXPECT_EQ(road.at("observability").at("planar"), true);
  EXPECT_EQ(road.at("observability").at("mean_axis"), nlohmann::json({0.0, 1.0, 0.0}));
  EXPECT_TRUE(road.at("observability").at("axis_std_ratio").is_null());  // infinite
  EXPECT_DOUBLE_EQ(road.at("observability").at("tilt_snr").get<double>(), 1.05);
  EXPECT_NEAR(road.at("errors").at("axis_err").get<double>(), 0.3, 1e-12);
  EXPECT_NEAR(road.at("errors").at("plane_err").get<double>(), 0.0, 1e-12);

  EXPECT_EQ(still.at("termination"), "insufficient_motion");
  EXPECT_EQ(still.at("message"), "need >= 2 motions with rotation >= 2 deg, got 1");
}

TEST(ResultJsonTest, NoTruthNoErrors) {
  const Fixture f = MakeFixture();
  const nlohmann::json j = ResultToJson(f.result, nullptr);
  for (const auto& slave : j.at("slaves")) EXPECT_FALSE(slave.contains("errors")) << slave.dump();
  // A truth map without the slave: no errors for that slave only.
  std::map<std::string, Similarity> partial = {{"back", f.truth.at("back")}};
  const nlohmann::json p = ResultToJson(f.result, &partial);
  EXPECT_FALSE(p.at("slaves")[0].contains("errors"));
  EXPECT_TRUE(p.at("slaves")[1].contains("errors"));
}

TEST(ResultJsonTest, SerialisesAndParsesBack) {
  const Fixture f = MakeFixture();
  const nlohmann::json j = ResultToJson(f.result, &f.truth);
  EXPECT_EQ(nlohmann::json::parse(j.dump()), j);
}

// A covariance that was not computed (or failed) leaves every σ unknown: null in JSON,
// "unknown" in the table, and the state usable, never converged.
TEST(ResultJsonTest, UnknownSigmaIsNullAndNotConverged) {
  DriveOptions d;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {DemoRig()[0]}, d);
  CalibrationOptions o;
  o.compute_covariance = false;
  const RigCalibration result = CalibrateRig(drive.recording, o);
  ASSERT_EQ(result.slaves.size(), 1u);
  EXPECT_EQ(result.slaves[0].state, SlaveState::kUsable) << result.slaves[0].message;
  const nlohmann::json j = ResultToJson(result, nullptr);
  const nlohmann::json& left = j.at("slaves")[0];
  EXPECT_EQ(left.at("state"), "usable");
  EXPECT_TRUE(left.at("std").at("rot_deg").is_null()) << left.dump();
  EXPECT_EQ(left.at("std").at("pos"), nlohmann::json({nullptr, nullptr, nullptr}));
  if (left.contains("scales")) {  // one σ per scale
    for (const auto& seg : left.at("scales")) EXPECT_TRUE(seg.at("std").is_null()) << left.dump();
  } else {
    EXPECT_TRUE(left.at("std").at("scale").is_null()) << left.dump();
  }
  const std::string table = FormatResultTable(result, nullptr);
  EXPECT_NE(table.find("std rotation [deg]    unknown"), std::string::npos) << table;
  EXPECT_EQ(table.find("nan"), std::string::npos) << table;
}

TEST(RollPitchYawTest, KnownRotations) {
  auto rpy = [](const Eigen::Quaterniond& q) { return RollPitchYawDeg(q); };
  // 1e-9 deg: a handful of double roundings in acos/atan2.
  EXPECT_LT((rpy(AxisAngle({0, 0, 1}, 90 * kRadPerDeg)) - Eigen::Vector3d(0, 0, 90)).norm(), 1e-9);
  EXPECT_LT((rpy(AxisAngle({1, 0, 0}, 30 * kRadPerDeg)) - Eigen::Vector3d(30, 0, 0)).norm(), 1e-9);
  EXPECT_LT((rpy(AxisAngle({0, 1, 0}, -20 * kRadPerDeg)) - Eigen::Vector3d(0, -20, 0)).norm(),
            1e-9);
  const Eigen::Quaterniond zyx = AxisAngle({0, 0, 1}, 40 * kRadPerDeg) *
                                 AxisAngle({0, 1, 0}, -20 * kRadPerDeg) *
                                 AxisAngle({1, 0, 0}, 10 * kRadPerDeg);
  EXPECT_LT((rpy(zyx) - Eigen::Vector3d(10, -20, 40)).norm(), 1e-9);
}

TEST(RollPitchYawTest, GimbalLockIsDeterministic) {
  // At pitch exactly ±90 only yaw - roll is defined: reported with roll 0.
  for (const double pitch : {90.0, -90.0}) {
    const Eigen::Quaterniond q =
        AxisAngle({0, 0, 1}, 30 * kRadPerDeg) * AxisAngle({0, 1, 0}, pitch * kRadPerDeg);
    const Eigen::Vector3d rpy = RollPitchYawDeg(q);
    EXPECT_NEAR(rpy.x(), 0.0, 1e-9) << rpy.transpose();
    EXPECT_NEAR(rpy.y(), pitch, 1e-6) << rpy.transpose();
    EXPECT_NEAR(rpy.z(), 30.0, 1e-6) << rpy.transpose();
  }
}

// The rotation Rz(30) Ry(pitch) Rx(20) swept through pitch 90 (and -90): roll and yaw jump by
// 180 deg where pitch passes ±90 (pitch itself turns back), the axis and angle do not.
TEST(AxisAngleTest, ContinuousThroughGimbalLock) {
  for (const double lock : {90.0, -90.0}) {
    const double step = 0.001;  // deg of pitch per sample
    AxisAngleDegrees previous;
    Eigen::Vector3d previous_rpy = Eigen::Vector3d::Zero();
    double largest_rpy_jump = 0.0;
    for (int k = -200; k <= 200; ++k) {
      const double pitch = lock + k * step;
      const Eigen::Quaterniond q = AxisAngle({0, 0, 1}, 30 * kRadPerDeg) *
                                   AxisAngle({0, 1, 0}, pitch * kRadPerDeg) *
                                   AxisAngle({1, 0, 0}, 20 * kRadPerDeg);
      const AxisAngleDegrees a = AxisAngleDeg(q);
      EXPECT_NEAR(a.axis.norm(), 1.0, 1e-12);
      EXPECT_GE(a.angle_deg, 0.0);
      EXPECT_LE(a.angle_deg, 180.0);
      // The axis and angle give back the rotation.
      EXPECT_LT(AngleBetween(AxisAngle(a.axis, a.angle_deg * kRadPerDeg), q) * kDegPerRad, 1e-9);
      const Eigen::Vector3d rpy = RollPitchYawDeg(q);
      if (k > -200) {
        // One step of 0.001 deg moves the rotation by 0.001 deg: the angle by at most that, the
        // axis by at most that over sin(angle / 2) (here angle > 90 deg: < 0.002 deg).
        EXPECT_LE(std::abs(a.angle_deg - previous.angle_deg), step + 1e-9) << pitch;
        const double axis_turn =
            std::atan2(a.axis.cross(previous.axis).norm(), a.axis.dot(previous.axis)) * kDegPerRad;
        EXPECT_LT(axis_turn, 2.0 * step) << pitch;
        largest_rpy_jump = std::max(largest_rpy_jump, (rpy - previous_rpy).cwiseAbs().maxCoeff());
      }
      previous = a;
      previous_rpy = rpy;
    }
    // Roll/pitch/yaw do flip here (what the axis and angle are printed for).
    EXPECT_GT(largest_rpy_jump, 90.0) << lock;
  }
}

TEST(AxisAngleTest, KnownRotationsAndJson) {
  const AxisAngleDegrees identity = AxisAngleDeg(Eigen::Quaterniond::Identity());
  EXPECT_EQ(identity.angle_deg, 0.0);
  EXPECT_EQ(identity.axis, Eigen::Vector3d::UnitZ());
  // -q is the same rotation: the representative with w >= 0, angle in [0, 180].
  const Eigen::Quaterniond q = AxisAngle({1, 2, 2}, -120 * kRadPerDeg);
  const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  for (const Eigen::Quaterniond& r : {q, minus_q}) {
    const AxisAngleDegrees a = AxisAngleDeg(r);
    EXPECT_NEAR(a.angle_deg, 120.0, 1e-9);
    EXPECT_LT((a.axis - Eigen::Vector3d(-1, -2, -2) / 3.0).norm(), 1e-12);
  }

  // JSON: every slave carries roll/pitch/yaw and axis/angle; "left" sits at pitch -89.5.
  const Fixture f = MakeFixture();
  const nlohmann::json j = ResultToJson(f.result, &f.truth);
  const nlohmann::json& left = j.at("slaves")[0];
  ASSERT_TRUE(left.contains("axis_angle")) << left.dump();
  EXPECT_NEAR(left["axis_angle"]["angle_deg"].get<double>(), 89.5, 1e-9);
  EXPECT_EQ(left["axis_angle"]["axis"], nlohmann::json({0.0, -1.0, 0.0}));
  EXPECT_NEAR(left["roll_pitch_yaw_deg"][1].get<double>(), -89.5, 1e-9);
  // The table shows both, and warns that roll and yaw are not unique near pitch ±90.
  const std::string table = FormatResultTable(f.result, &f.truth);
  EXPECT_THAT(table,
              ::testing::ContainsRegex(
                  "axis, angle \\[deg\\] +-?0\\.000000 +-1\\.000000 +-?0\\.000000 +89\\.5000"));
  EXPECT_THAT(table, HasSubstr("roll and yaw are not unique"));
}

TEST(TruthAlignmentTest, AppliedAlignmentInJsonAndTable) {
  Fixture f = MakeFixture();
  f.result.slaves[1].position_observable = false;  // back: translational, no C estimated
  // The truth in metres, the master unit 0.37 m: C and scales times 0.37.
  std::map<std::string, Similarity> metric = f.truth;
  for (auto& [name, rig] : metric) {
    rig.C *= 0.37;
    rig.scale *= 0.37;
  }
  const TruthAlignment a = AlignTruthUnit(f.result, metric, TruthUnit::kAuto);
  ASSERT_TRUE(a.applied) << a.message;
  EXPECT_NEAR(a.metres_per_unit, 0.37, 0.005) << a.message;
  // left and road (in the plane) have positions; back is translational, still not usable.
  EXPECT_EQ(a.slaves_used, std::vector<std::string>({"left", "road"}));
  const std::map<std::string, Similarity> aligned = TruthInMasterUnits(metric, a);
  // Aligned from the mountings alone, a slave's odometry unit is unknown: no true scale.
  EXPECT_TRUE(std::isnan(aligned.at("left").scale));

  const nlohmann::json j = ResultToJson(f.result, &aligned, &a);
  ASSERT_TRUE(j.contains("truth_alignment")) << j.dump(2);
  const nlohmann::json& t = j["truth_alignment"];
  EXPECT_EQ(Keys(t),
            std::set<std::string>({"mode", "applied", "metres_per_master_unit", "std", "fit_rms_m",
                                   "slaves_used", "slave_excluded", "message"}));
  EXPECT_EQ(t["mode"], "auto");
  EXPECT_EQ(t["applied"], true);
  EXPECT_EQ(t["metres_per_master_unit"], a.metres_per_unit);
  EXPECT_TRUE(t["slave_excluded"].is_null());
  const nlohmann::json& errors = j["slaves"][0]["errors"];
  EXPECT_NEAR(errors["trans_err_m"].get<double>(),
              errors["trans_err"].get<double>() * a.metres_per_unit, 1e-15);

  const std::string table = FormatResultTable(f.result, &aligned, &a);
  EXPECT_THAT(table, HasSubstr("truth: positions compared after aligning the master unit to the "
                               "truth: 1 master unit = 0.3"));
  EXPECT_THAT(table, ::testing::ContainsRegex("C error [0-9.e-]+ master units \\([0-9.e-]+ m\\)"));
  EXPECT_THAT(table, HasSubstr("scale not compared (the slave's odometry unit is unknown)"));
  EXPECT_TRUE(errors["scale_pct"].is_null()) << errors.dump();

  // Without an alignment: no truth_alignment, no trans_err_m (the schema as before).
  const nlohmann::json plain = ResultToJson(f.result, &f.truth);
  EXPECT_FALSE(plain.contains("truth_alignment"));
  EXPECT_FALSE(plain["slaves"][0]["errors"].contains("trans_err_m"));
}

TEST(TruthAlignmentTest, TruthInMasterUnitsIsNotAligned) {
  const Fixture f = MakeFixture();
  const TruthAlignment a = AlignTruthUnit(f.result, f.truth, TruthUnit::kAuto);
  EXPECT_FALSE(a.applied) << a.message;
  EXPECT_NEAR(a.metres_per_unit, 1.0, 0.02);
  EXPECT_THAT(a.message, HasSubstr("the truth is in master units"));
  const nlohmann::json j = ResultToJson(f.result, &f.truth, &a);
  EXPECT_EQ(j["truth_alignment"]["applied"], false);
  EXPECT_FALSE(j["slaves"][0]["errors"].contains("trans_err_m"));
  // Forced: the same truth declared metric is aligned (by a unit close to 1).
  EXPECT_TRUE(AlignTruthUnit(f.result, f.truth, TruthUnit::kMetric).applied);
  // Declared in master units: never aligned, whatever the fit says.
  std::map<std::string, Similarity> metric = f.truth;
  for (auto& [name, rig] : metric) rig.C *= 0.37;
  const TruthAlignment master = AlignTruthUnit(f.result, metric, TruthUnit::kMaster);
  EXPECT_FALSE(master.applied);
  EXPECT_NEAR(master.metres_per_unit, 0.37, 0.005);
}

// Four slaves, one of which has a position estimate 30 % off: with 3 or more slaves that one is
// left out of the unit's fit, which then is the others' unit.
TEST(TruthAlignmentTest, OneBadSlaveIsLeftOut) {
  RigCalibration result;
  std::map<std::string, Similarity> metric;
  const std::vector<Eigen::Vector3d> centres = {
      {0.5, 0.0, 0.1}, {-0.4, 0.2, 0.0}, {0.0, -0.3, 0.6}, {0.3, 0.3, -0.3}};
  const double unit = 0.37;  // metres per master unit
  for (size_t i = 0; i < centres.size(); ++i) {
    SlaveCalibration s;
    s.name = "cam" + std::to_string(i + 1);
    s.estimate.C = centres[i] + Eigen::Vector3d(1e-4, -1e-4, 2e-4) * static_cast<double>(i);
    if (i == 2) s.estimate.C *= 1.3;
    s.pos_std = Eigen::Vector3d::Constant(1e-4);
    s.termination = Termination::kSolved;
    s.state = SlaveState::kConverged;
    result.slaves.push_back(s);
    Similarity t;
    t.C = centres[i] * unit;
    metric[s.name] = t;
  }
  const TruthAlignment a = AlignTruthUnit(result, metric, TruthUnit::kAuto);
  ASSERT_TRUE(a.applied) << a.message;
  EXPECT_EQ(a.slave_excluded, "cam3") << a.message;
  EXPECT_EQ(a.slaves_used, std::vector<std::string>({"cam1", "cam2", "cam4"}));
  EXPECT_NEAR(a.metres_per_unit, unit, 1e-3) << a.message;
  EXPECT_THAT(a.message, HasSubstr("cam3 left out"));
  // All four good: none left out.
  result.slaves[2].estimate.C = centres[2];
  const TruthAlignment good = AlignTruthUnit(result, metric, TruthUnit::kAuto);
  EXPECT_TRUE(good.slave_excluded.empty()) << good.message;
  EXPECT_EQ(good.slaves_used.size(), 4u);
  EXPECT_NEAR(good.metres_per_unit, unit, 1e-3);
}

TEST(FormatResultTableTest, ShowsEstimatesTruthAndErrors) {
  const Fixture f = MakeFixture();
  const std::string table = FormatResultTable(f.result, &f.truth);
  for (const char* expected : {"master: front",
                               "left: converged",
                               "back: converged",
                               "still: initialising (insufficient_motion)",
                               "NOT USABLE",
                               "need >= 2 motions with rotation >= 2 deg, got 1",
                               "q (w, x, y, z)",
                               "roll pitch yaw [deg]",
                               "axis, angle [deg]",
                               "C [master units]",
                               "truth",
                               "scale segment 3",
                               "std rotation",
                               "used 190 of 200, rejected 10",
                               "3 poses dropped (position jump 2, rotation jump 0, angle "
                               "mismatch 1; in the master 1, in this camera 2)",
                               "motion general, scale fixed",
                               "motion translational, scale segments",
                               "unobservable along",
                               "errors vs truth",
                               "rotation 0.5 deg",
                               "scale 1 %",
                               "motion planar, scale fixed",
                               "C along mean axis",
                               "unobservable: unknown (0 shown; give a nominal)",
                               "tilt SNR 1.05",
                               "C error in the plane 0, along the mean axis 0.3"}) {
    EXPECT_THAT(table, HasSubstr(expected));
  }
  // left's estimate -0.84 and its truth -0.85 both appear in its C row.
  EXPECT_THAT(table, ::testing::ContainsRegex("C \\[master units\\] +-0\\.8400 .* -0\\.8500"));
}

TEST(FormatResultTableTest, NoTruthNoTruthColumn) {
  const Fixture f = MakeFixture();
  const std::string table = FormatResultTable(f.result, nullptr);
  EXPECT_THAT(table, Not(HasSubstr("truth")));
  EXPECT_THAT(table, HasSubstr("left: converged"));
}

}  // namespace
}  // namespace rigcal::io
