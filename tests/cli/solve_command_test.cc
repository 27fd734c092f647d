// SPDX-License-Identifier: Apache-2.0
// End-to-end tests of `rigcal solve`: runs the built binary on synthetic TUM files of a
// 3-camera rig drive and checks exit codes, the JSON schema, the written files and accuracy.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/command_test.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/synthetic_car.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/trajectory_io.h"
#include "support/skip.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using cli_test::Quote;
using cli_test::RunResult;
using cli_test::Slurp;

class SolveCommandTest : public cli_test::CommandTest {
 protected:
  // Writes cam0.txt (master), cam1.txt, cam2.txt and truth.yaml of the demo rig drive.
  void WriteDemoDrive(int64_t slave_time_offset_ns = 0) {
    const std::vector<std::string> names = {"cam0", "cam1", "cam2"};
    const SyntheticDrive drive = GenerateDrive(names, DemoRig(), DriveOptions{});
    const RigRecording& rec = drive.recording;
    WriteTrack(rec, rec.master, 0);
    for (const CameraTrack& slave : rec.slaves) WriteTrack(rec, slave, slave_time_offset_ns);
    std::map<std::string, Similarity> truth;
    for (size_t i = 0; i < drive.truth.size(); ++i) truth[names[i + 1]] = drive.truth[i];
    ASSERT_TRUE(io::WriteRigYaml(Path("truth.yaml"), truth).ok());
    truth_ = truth;
  }

  void WriteTrack(const RigRecording& rec, const CameraTrack& track, int64_t offset_ns) {
    TimedTrajectory t;
    t.name = track.name;
    for (const int64_t stamp : rec.t_ns) t.t_ns.push_back(stamp + offset_ns);
    t.poses = track.poses;
    t.segment = track.segment;
    ASSERT_TRUE(io::WriteTrajectoryTum(Path(track.name + ".txt"), t).ok());
  }

  std::string DemoArgs() const {
    return "solve --master " + Quote(Path("cam0.txt")) + " --slave " + Quote(Path("cam1.txt")) +
           " --slave " + Quote(Path("cam2.txt"));
  }

  std::map<std::string, Similarity> truth_;
};

std::string Explain(const RunResult& r) {
  return "exit " + std::to_string(r.exit_code) + "\n--- stdout:\n" + r.out + "\n--- stderr:\n" +
         r.err;
}

nlohmann::json ParseJson(const RunResult& r) {
  const auto j = nlohmann::json::parse(r.out, nullptr, /*allow_exceptions=*/false);
  EXPECT_FALSE(j.is_discarded()) << "stdout is not one JSON object\n" << Explain(r);
  return j;
}

// Rotation angle in degrees between the rotation blocks of two 4x4 transforms.
double RotationDifferenceDeg(const Eigen::Matrix4d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d ra = a.topLeftCorner<3, 3>();
  return RotationAngle(Eigen::Quaterniond(ra.transpose() * b)) * kDegPerRad;
}

TEST_F(SolveCommandTest, SolvesDemoRigWithJsonOutAndCamchain) {
  WriteDemoDrive();
  const RunResult r =
      Run(DemoArgs() + " --truth " + Quote(Path("truth.yaml")) + " --json" + " --out " +
          Quote(Path("result.yaml")) + " --camchain " + Quote(Path("camchain.yaml")));
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const nlohmann::json j = ParseJson(r);
  ASSERT_TRUE(j.is_object()) << Explain(r);
  EXPECT_EQ(j.value("master", ""), "cam0");
  ASSERT_TRUE(j.contains("slaves") && j["slaves"].is_array()) << j.dump(2);
  ASSERT_EQ(j["slaves"].size(), 2u) << j.dump(2);

  const auto out_yaml = io::ReadRigYaml(Path("result.yaml"));
  ASSERT_TRUE(out_yaml.ok()) << out_yaml.error();
  EXPECT_EQ(out_yaml->size(), 2u);

  for (size_t i = 0; i < 2; ++i) {
    const nlohmann::json& s = j["slaves"][i];
    const std::string name = "cam" + std::to_string(i + 1);
    SCOPED_TRACE(name);
    EXPECT_EQ(s.value("name", ""), name);
    for (const char* key : {"q_wxyz", "C", "scale", "std", "motions_used", "motions_rejected",
                            "models", "termination", "message", "unobservable", "errors"}) {
      EXPECT_TRUE(s.contains(key)) << key << " missing in " << s.dump(2);
    }
    ASSERT_TRUE(s.contains("errors")) << s.dump(2);
    EXPECT_EQ(s.value("termination", ""), "solved");
    EXPECT_EQ(s.value("state", ""), "converged");
    EXPECT_EQ(s["models"].value("motion", ""), "general");
    EXPECT_GE(s.value("motions_used", 0), 2);
    // The drive has 0.05 deg rotation noise and 2 mm position noise per pose over ~1200
    // poses: the estimate is far better than these bounds (the brief's acceptance limits);
    // exceeding them means a broken pipeline, not noise.
    EXPECT_LT(s["errors"].value("rot_deg", 1e9), 0.5);
    EXPECT_LT(s["errors"].value("scale_pct", 1e9), 2.0);
    EXPECT_LT(s["errors"].value("trans_err", 1e9), 0.05);  // master units; |C| ~ 1-2.2

    // --out round trip: the YAML holds the same numbers as the JSON (both print round-trip
    // digits; only the re-normalisation of q on reading changes the last bits).
    ASSERT_EQ(out_yaml->count(name), 1u);
    const Similarity& y = out_yaml->at(name);
    const auto q = s["q_wxyz"].get<std::vector<double>>();
    const auto c = s["C"].get<std::vector<double>>();
    ASSERT_EQ(q.size(), 4u);
    ASSERT_EQ(c.size(), 3u);
    EXPECT_NEAR(y.q.w(), q[0], 1e-12);
    EXPECT_NEAR(y.q.x(), q[1], 1e-12);
    EXPECT_NEAR(y.q.y(), q[2], 1e-12);
    EXPECT_NEAR(y.q.z(), q[3], 1e-12);
    EXPECT_EQ(y.C, Eigen::Vector3d(c[0], c[1], c[2]));
    EXPECT_EQ(y.scale, s["scale"].get<double>());
  }

  // --camchain: parseable, cameras in --slave order, rotations consistent with the truth:
  // T_c1_c0 rotates by R1^T and T_c2_c1 by R2^T R1 (two estimates, so twice the 0.5 deg).
  const auto chain = io::ReadCamchain(Path("camchain.yaml"));
  ASSERT_TRUE(chain.ok()) << chain.error();
  ASSERT_EQ(chain->size(), 3u);
  EXPECT_EQ((*chain)[0].name, "cam0");
  EXPECT_EQ((*chain)[1].name, "cam1");
  EXPECT_EQ((*chain)[2].name, "cam2");
  const Eigen::Matrix3d r1 = truth_.at("cam1").q.toRotationMatrix();
  const Eigen::Matrix3d r2 = truth_.at("cam2").q.toRotationMatrix();
  EXPECT_LT(RotationDifferenceDeg((*chain)[1].cn_from_cnm1, r1.transpose()), 0.5);
  EXPECT_LT(RotationDifferenceDeg((*chain)[2].cn_from_cnm1, r2.transpose() * r1), 1.0);
}

// --camchain with a config holding the cameras' intrinsics and a metric master: a camchain
// Kalibr's config reader loads (tests/io/kalibr_camchain_reader.py follows its schema), in
// metres; without the unit the file says the translations are in master units.
TEST_F(SolveCommandTest, CamchainLoadsAsKalibrCamchain) {
  if (std::system("python3 -c 'import yaml' 2>/dev/null") != 0) {
    RIGCAL_SKIP_MISSING() << "python3 with yaml (python3-yaml) not installed";
  }
  WriteDemoDrive();
  std::string config = "rig: {name: demo, master: cam0}\ncameras:\n";
  for (const std::string name : {"cam0", "cam1", "cam2"}) {
    config += "  - name: " + name +
              "\n    model: pinhole\n    resolution: [752, 480]\n"
              "    intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
              "    distortion: [-0.28, 0.07, 0.0002, 0.00002]\n";
  }
  std::ofstream(Path("rig.yaml")) << config;
  const std::string reader = std::string(RIGCAL_SOURCE_DIR) + "/tests/io/kalibr_camchain_reader.py";
  const RunResult metric = Run(DemoArgs() + " --master-metric --config " + Quote(Path("rig.yaml")) +
                               " --camchain " + Quote(Path("metric.yaml")));
  ASSERT_EQ(metric.exit_code, 0) << Explain(metric);
  const RunResult loaded = cli_test::RunShell(
      "python3 " + Quote(reader) + " " + Quote(Path("metric.yaml")) + " --metric", dir_);
  EXPECT_EQ(loaded.exit_code, 0) << Explain(loaded);

  const RunResult plain = Run(DemoArgs() + " --camchain " + Quote(Path("plain.yaml")));
  ASSERT_EQ(plain.exit_code, 0) << Explain(plain);
  EXPECT_THAT(plain.err, HasSubstr("translations in the master odometry's unit, not metres"));
  EXPECT_THAT(plain.err, HasSubstr("no intrinsics for cam0, cam1, cam2"));
  const RunResult refused =
      cli_test::RunShell("python3 " + Quote(reader) + " " + Quote(Path("plain.yaml")), dir_);
  EXPECT_EQ(refused.exit_code, 1) << Explain(refused);  // the reader can fail
  EXPECT_THAT(refused.err, HasSubstr("cam0: no camera_model"));
}

TEST_F(SolveCommandTest, TextOutputShowsErrorsAgainstTruth) {
  WriteDemoDrive();
  const RunResult r = Run(DemoArgs() + " --truth " + Quote(Path("truth.yaml")));
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  for (const char* expected : {"master: cam0", "cam1: converged", "cam2: converged",
                               "roll pitch yaw [deg]", "errors vs truth", "truth"}) {
    EXPECT_THAT(r.out, HasSubstr(expected)) << Explain(r);
  }
}

// The demo drive read as a monocular recording whose master unit is 0.37 m, its truth written
// in metres (C and the scales, slave unit -> metres, times 0.37): the errors are printed after
// fitting the master unit to the truth, small against the printed σ, and the output says so.
constexpr double kMasterUnitM = 0.37;

std::map<std::string, Similarity> InMetres(std::map<std::string, Similarity> truth) {
  for (auto& [name, rig] : truth) {
    rig.C *= kMasterUnitM;
    rig.scale *= kMasterUnitM;
  }
  return truth;
}

TEST_F(SolveCommandTest, MetricTruthIsComparedAfterAligningTheMasterUnit) {
  WriteDemoDrive();
  ASSERT_TRUE(io::WriteRigYaml(Path("metric.yaml"), InMetres(truth_)).ok());
  const RunResult r = Run(DemoArgs() + " --truth " + Quote(Path("metric.yaml")) + " --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const nlohmann::json j = ParseJson(r);
  ASSERT_TRUE(j.contains("truth_alignment")) << j.dump(2);
  const nlohmann::json& a = j["truth_alignment"];
  EXPECT_EQ(a.value("mode", ""), "auto");
  EXPECT_EQ(a.value("applied", false), true) << a.dump(2);
  const double k = a.value("metres_per_master_unit", 0.0);
  const double k_std = a.value("std", 0.0);
  EXPECT_GT(k_std, 0.0) << a.dump(2);
  EXPECT_NEAR(k, kMasterUnitM, 4.0 * k_std + 1e-9) << a.dump(2);
  EXPECT_EQ(a["slaves_used"], nlohmann::json({"cam1", "cam2"}));
  EXPECT_THAT(a.value("message", ""),
              HasSubstr("positions compared after aligning the master unit to the truth"));
  for (const auto& s : j["slaves"]) {
    const std::string name = s.value("name", "");
    ASSERT_TRUE(s.contains("errors")) << s.dump(2);
    const nlohmann::json& e = s["errors"];
    // Tolerances from the printed σ: the estimate's own (4 σ) plus what the unit's σ moves the
    // aligned truth by (|C_true| σ_k / k in C, σ_k / k in the scale).
    const Eigen::Vector3d pos_std(s["std"]["pos"][0].get<double>(),
                                  s["std"]["pos"][1].get<double>(),
                                  s["std"]["pos"][2].get<double>());
    const double c_true = truth_.at(name).C.norm();  // master units
    EXPECT_LT(e.value("rot_deg", 1e9), 4.0 * s["std"].value("rot_deg", 0.0) + 1e-6) << s.dump(2);
    const double c_tolerance = 4.0 * (pos_std.norm() + c_true * k_std / k);
    EXPECT_LT(e.value("trans_err", 1e9), c_tolerance) << s.dump(2);
    EXPECT_NEAR(e.value("trans_err_m", 1e9), e.value("trans_err", 0.0) * k, 1e-12);
    EXPECT_LT(e.value("dist_pct", 1e9), 100.0 * c_tolerance / c_true) << s.dump(2);
    // Aligned from the mountings alone, a slave's odometry unit is not known: no scale error
    // (truth_comparison.h; with the true trajectories it is, per segment).
    EXPECT_TRUE(e["scale_pct"].is_null()) << s.dump(2);
  }

  // Text: the alignment line with the unit, the truth columns in master units, C errors in m.
  const RunResult text = Run(DemoArgs() + " --truth " + Quote(Path("metric.yaml")));
  ASSERT_EQ(text.exit_code, 0) << Explain(text);
  EXPECT_THAT(text.out, ::testing::ContainsRegex(
                            "truth: positions compared after aligning the master unit to the "
                            "truth: 1 master unit = 0\\.3[67][0-9]* m \\(± [0-9.e-]+, least "
                            "squares of the truth's C on the estimated C of cam1, cam2\\)"))
      << Explain(text);
  EXPECT_THAT(text.out,
              ::testing::ContainsRegex("C error [0-9.e-]+ master units \\([0-9.e-]+ m\\)"))
      << Explain(text);
  EXPECT_THAT(text.out, HasSubstr("axis, angle [deg]"));
}

TEST_F(SolveCommandTest, TruthInMasterUnitsIsComparedAsGiven) {
  WriteDemoDrive();
  const RunResult r = Run(DemoArgs() + " --truth " + Quote(Path("truth.yaml")) + " --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const nlohmann::json j = ParseJson(r);
  const nlohmann::json& a = j["truth_alignment"];
  EXPECT_EQ(a.value("applied", true), false) << a.dump(2);
  EXPECT_NEAR(a.value("metres_per_master_unit", 0.0), 1.0, 0.02) << a.dump(2);
  EXPECT_THAT(a.value("message", ""), HasSubstr("the truth is in master units"));
  for (const auto& s : j["slaves"]) {
    EXPECT_FALSE(s["errors"].contains("trans_err_m")) << s.dump(2);
    EXPECT_LT(s["errors"].value("trans_err", 1e9), 0.05) << s.dump(2);
  }

  // Declared in master units, a metric truth is not aligned: its C are 0.37 times too short.
  ASSERT_TRUE(io::WriteRigYaml(Path("metric.yaml"), InMetres(truth_)).ok());
  const RunResult forced =
      Run(DemoArgs() + " --truth " + Quote(Path("metric.yaml")) + " --truth-unit master --json");
  ASSERT_EQ(forced.exit_code, 0) << Explain(forced);
  const nlohmann::json f = ParseJson(forced);
  EXPECT_EQ(f["truth_alignment"].value("applied", true), false);
  EXPECT_EQ(f["truth_alignment"].value("mode", ""), "master");
  for (const auto& s : f["slaves"]) {
    EXPECT_GT(s["errors"].value("dist_pct", 0.0), 100.0 * (1.0 / kMasterUnitM - 1.0) * 0.9)
        << s.dump(2);
  }
  // --truth-unit needs --truth.
  const RunResult alone = Run(DemoArgs() + " --truth-unit metric");
  EXPECT_EQ(alone.exit_code, 2) << Explain(alone);
}

TEST_F(SolveCommandTest, OnlineConvergenceErrorsUseTheAlignedTruth) {
  WriteDemoDrive();
  ASSERT_TRUE(io::WriteRigYaml(Path("metric.yaml"), InMetres(truth_)).ok());
  const RunResult r =
      Run(DemoArgs() + " --online --truth " + Quote(Path("metric.yaml")) + " --truth-unit metric");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  EXPECT_THAT(r.out, HasSubstr("convergence errors in master units, the truth aligned: "
                               "positions compared after aligning the master unit"))
      << Explain(r);
}

TEST_F(SolveCommandTest, OptionsReachTheCalibrator) {
  WriteDemoDrive();
  const RunResult r = Run(DemoArgs() +
                          " --method lls --motion general --scale partitions:3"
                          " --pairs relative:20 --json");
  ASSERT_EQ(r.exit_code, 0) << Explain(r);
  const nlohmann::json j = ParseJson(r);
  ASSERT_TRUE(j.contains("slaves")) << Explain(r);
  for (const auto& s : j["slaves"]) {
    EXPECT_EQ(s["models"].value("motion", ""), "general") << s.dump(2);
    EXPECT_EQ(s["models"].value("scale", ""), "partitions") << s.dump(2);
    ASSERT_TRUE(s.contains("scales")) << s.dump(2);
    EXPECT_EQ(s["scales"].size(), 3u) << s.dump(2);
    EXPECT_FALSE(s.contains("errors"));  // no --truth
  }
}

TEST_F(SolveCommandTest, StampsBeyondTheToleranceAreInterpolated) {
  // 3 ms: not coinciding with the master's stamps, so interpolated whatever the tolerance.
  WriteDemoDrive(/*slave_time_offset_ns=*/3'000'000);
  for (const char* tolerance : {"5", "1"}) {
    const RunResult r = Run(DemoArgs() + " --tolerance-ms " + tolerance + " --json");
    EXPECT_EQ(r.exit_code, 0) << Explain(r);
  }
}

TEST_F(SolveCommandTest, BadLineNamesFileAndLine) {
  WriteDemoDrive();
  // Corrupt the 4th pose line (line 5: the writer puts a comment on line 1).
  std::vector<std::string> lines;
  {
    std::ifstream in(Path("cam1.txt"));
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  lines[4] = "0.15 1 2 3 x 0 0 1";
  {
    std::ofstream out(Path("cam1.txt"));
    for (const auto& l : lines) out << l << "\n";
  }
  const RunResult r = Run(DemoArgs());
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: " + Path("cam1.txt") + ":5: column 5 (qx)"));
  EXPECT_EQ(r.out, "");
}

TEST_F(SolveCommandTest, MissingFile) {
  WriteDemoDrive();
  const RunResult r = Run(DemoArgs() + " --slave " + Quote(Path("cam9.txt")));
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: " + Path("cam9.txt") + ": cannot open"));
}

TEST_F(SolveCommandTest, TruthWithoutSlaveNamesTheSlave) {
  WriteDemoDrive();
  ASSERT_TRUE(io::WriteRigYaml(Path("partial.yaml"), {{"cam1", truth_.at("cam1")}}).ok());
  const RunResult r = Run(DemoArgs() + " --truth " + Quote(Path("partial.yaml")));
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr(Path("partial.yaml") + ": no entry for slave 'cam2'"));
}

TEST_F(SolveCommandTest, BadTruthFileNamesFieldAndLine) {
  WriteDemoDrive();
  std::ofstream(Path("bad.yaml")) << "cam1:\n  q_wxyz: [1, 0, 0]\n  C: [0, 0, 0]\n  scale: 1\n";
  const RunResult r = Run(DemoArgs() + " --truth " + Quote(Path("bad.yaml")));
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: " + Path("bad.yaml") + ":2: cam1.q_wxyz"));
}

TEST_F(SolveCommandTest, NoOverlappingTimeRange) {
  WriteDemoDrive(/*slave_time_offset_ns=*/1'000'000'000'000);
  const RunResult r = Run(DemoArgs());
  EXPECT_EQ(r.exit_code, 1) << Explain(r);
  EXPECT_THAT(r.err,
              HasSubstr("rigcal solve: no overlapping time range: master cam0 0.000..59.950 s"));
  EXPECT_THAT(r.err, HasSubstr("cam1 1000.000..1059.950 s"));
}

TEST_F(SolveCommandTest, UnusableSlaveExitsWith3AndStillWritesTheResult) {
  // A rig that only translates: the general motion model (forced) has no motion with enough
  // rotation, so the slave has no usable estimate.
  Similarity rig;
  rig.q = AxisAngle(Eigen::Vector3d::UnitY(), 0.5);
  rig.C = Eigen::Vector3d(0.3, 0.0, -0.2);
  rig.scale = 0.7;
  TimedTrajectory master, slave;
  for (int k = 0; k < 100; ++k) {
    Pose p;
    p.C = Eigen::Vector3d(0.05 * k, 0.01 * std::sin(0.1 * k), 0.0);
    master.t_ns.push_back(k * 50'000'000LL);
    master.poses.push_back(p);
    master.segment.push_back(0);
    slave.t_ns.push_back(k * 50'000'000LL);
    slave.poses.push_back(SlavePoseFromMaster(p, rig));
    slave.segment.push_back(0);
  }
  ASSERT_TRUE(io::WriteTrajectoryTum(Path("m.txt"), master).ok());
  ASSERT_TRUE(io::WriteTrajectoryTum(Path("s.txt"), slave).ok());
  const RunResult r =
      Run("solve --master " + Quote(Path("m.txt")) + " --slave " + Quote(Path("s.txt")) +
          " --motion general --json --out " + Quote(Path("result.yaml")));
  EXPECT_EQ(r.exit_code, 3) << Explain(r);
  const nlohmann::json j = ParseJson(r);
  ASSERT_TRUE(j.contains("slaves") && j["slaves"].size() == 1u) << Explain(r);
  const std::string termination = j["slaves"][0].value("termination", "");
  EXPECT_TRUE(termination == "insufficient_motion" || termination == "degenerate") << termination;
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: s: initialising (" + termination + ")"));
  EXPECT_TRUE(fs::exists(Path("result.yaml")));
  EXPECT_THAT(Slurp(Path("result.yaml")), HasSubstr("usable: false"));
}

// Data that do not support a result exit with 3 and say what is missing (batch_acceptance):
// a "slave" that is the master's trajectory played backwards (no rig at all), and the planar
// model forced on 6-DoF motion.
TEST_F(SolveCommandTest, UnsupportedResultsExitWith3AndSayWhy) {
  DriveOptions d;
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.002;
  const SyntheticDrive drive = GenerateDrive({"m", "s"}, {DemoRig()[0]}, d);
  const RigRecording& rec = drive.recording;
  WriteTrack(rec, rec.master, 0);
  CameraTrack reversed = rec.master;
  reversed.name = "s";
  const size_t n = rec.size();
  for (size_t k = 0; k < n; ++k) {
    reversed.poses[k] = rec.master.poses[n - 1].Between(rec.master.poses[n - 1 - k]);
  }
  WriteTrack(rec, reversed, 0);
  const std::string inputs =
      "solve --master " + Quote(Path("m.txt")) + " --slave " + Quote(Path("s.txt"));
  RunResult r = Run(inputs + " --json");
  EXPECT_EQ(r.exit_code, 3) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: s: initialising (solved): not usable: the "
                               "trajectories are unrelated"))
      << Explain(r);
  const nlohmann::json j = ParseJson(r);
  ASSERT_TRUE(j.contains("slaves") && j["slaves"].size() == 1u) << Explain(r);
  EXPECT_EQ(j["slaves"][0].value("state", ""), "initialising") << Explain(r);

  WriteTrack(rec, rec.slaves[0], 0);  // the real slave
  r = Run(inputs + " --motion planar");
  EXPECT_EQ(r.exit_code, 3) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("the data contradict the planar model")) << Explain(r);
  EXPECT_THAT(r.err, HasSubstr("rigcal solve: s: initialising (solved): not usable: "))
      << Explain(r);
  r = Run(inputs);
  EXPECT_EQ(r.exit_code, 0) << Explain(r);
}

// A car rig (front master, left, right, rear) on a level road, yaw only: planar motion. The
// offset of every slave along the vertical (the cameras' y axis) is reported unknown, or taken
// from --prior (with --prior-sigma as its σ).
TEST_F(SolveCommandTest, PlanarCarDriveReportsTheVerticalAsUnobservable) {
  const SyntheticDrive drive = DriveCarRig(CarPath({.duration_s = 60.0, .rate_hz = 10.0}),
                                           {.rotation_noise_deg = 0.02, .position_noise = 0.01});
  const RigRecording& rec = drive.recording;
  WriteTrack(rec, rec.master, 0);
  std::string args = "solve --master " + Quote(Path("front.txt"));
  std::map<std::string, Similarity> truth, nominal;
  for (size_t i = 0; i < rec.slaves.size(); ++i) {
    WriteTrack(rec, rec.slaves[i], 0);
    args += " --slave " + Quote(Path(rec.slaves[i].name + ".txt"));
    truth[rec.slaves[i].name] = drive.truth[i];
    nominal[rec.slaves[i].name] = drive.truth[i];
    nominal[rec.slaves[i].name].C.y() += 0.05;  // CAD heights 5 cm off
  }
  ASSERT_TRUE(io::WriteRigYaml(Path("truth.yaml"), truth).ok());
  ASSERT_TRUE(io::WriteRigYaml(Path("nominal.yaml"), nominal).ok());
  args += " --truth " + Quote(Path("truth.yaml")) + " --json";

  const RunResult plain = Run(args);
  ASSERT_EQ(plain.exit_code, 0) << Explain(plain);
  const nlohmann::json j = ParseJson(plain);
  ASSERT_EQ(j["slaves"].size(), 3u) << Explain(plain);
  for (const auto& s : j["slaves"]) {
    SCOPED_TRACE(s.value("name", ""));
    EXPECT_EQ(s["models"].value("motion", ""), "planar") << s.dump(2);
    ASSERT_EQ(s["unobservable"].size(), 1u) << s.dump(2);
    EXPECT_NEAR(s["unobservable"][0][1].get<double>(), 1.0, 1e-6);  // the vertical (y down)
    EXPECT_EQ(s.value("unobservable_from_prior", true), false);
    EXPECT_TRUE(s["std"]["axis"].is_null()) << s.dump(2);
    EXPECT_EQ(s["observability"].value("planar", false), true);
    EXPECT_THAT(s.value("message", ""), HasSubstr("unobservable"));
    // C along the axis is reported as 0, not estimated: the error along it is the true height.
    const std::vector<double> axis = s["unobservable"][0].get<std::vector<double>>();
    const std::vector<double> c = s["C"].get<std::vector<double>>();
    EXPECT_NEAR(c[0] * axis[0] + c[1] * axis[1] + c[2] * axis[2], 0.0, 1e-12);
    const Similarity& t = truth.at(s.value("name", ""));
    EXPECT_NEAR(s["errors"]["axis_err"].get<double>(),
                std::abs(t.C.x() * axis[0] + t.C.y() * axis[1] + t.C.z() * axis[2]), 1e-9);
    // 1 cm / 0.02 deg pose noise on 600 poses: millimetres in the plane, hundredths of a degree.
    EXPECT_LT(s["errors"]["plane_err"].get<double>(), 0.03);
    EXPECT_LT(s["errors"]["rot_deg"].get<double>(), 0.05);
    EXPECT_LT(s["errors"]["scale_pct"].get<double>(), 0.1);
  }

  const RunResult with_prior = Run(args + " --prior " + Quote(Path("nominal.yaml")));
  ASSERT_EQ(with_prior.exit_code, 0) << Explain(with_prior);
  // The parsed document outlives the loop (a range-for over a member of a temporary does not).
  const nlohmann::json prior_json = ParseJson(with_prior);
  for (const auto& s : prior_json["slaves"]) {
    SCOPED_TRACE(s.value("name", ""));
    EXPECT_EQ(s.value("unobservable_from_prior", false), true) << s.dump(2);
    const std::vector<double> axis = s["unobservable"][0].get<std::vector<double>>();
    const std::vector<double> c = s["C"].get<std::vector<double>>();
    const Eigen::Vector3d n = nominal.at(s.value("name", "")).C;
    EXPECT_NEAR(c[0] * axis[0] + c[1] * axis[1] + c[2] * axis[2],
                n.x() * axis[0] + n.y() * axis[1] + n.z() * axis[2], 1e-9);
    EXPECT_NEAR(s["errors"]["axis_err"].get<double>(), 0.05, 1e-3);  // the CAD error
    EXPECT_THAT(s.value("message", ""), HasSubstr("nominal mounting"));
  }
  const RunResult with_sigma =
      Run(args + " --prior " + Quote(Path("nominal.yaml")) + " --prior-sigma 0.1");
  ASSERT_EQ(with_sigma.exit_code, 0) << Explain(with_sigma);
  const nlohmann::json sigma_json = ParseJson(with_sigma);
  for (const auto& s : sigma_json["slaves"]) {
    EXPECT_EQ(s["std"]["axis"].get<double>(), 0.1) << s.dump(2);
  }
  // The thesis's general model cannot do this: degenerate, exit 3, and it says why.
  const RunResult general = Run(args + " --motion general");
  EXPECT_EQ(general.exit_code, 3) << Explain(general);
  EXPECT_THAT(general.err, HasSubstr("planar model"));
}

TEST_F(SolveCommandTest, PriorSigmaNeedsAPrior) {
  WriteDemoDrive();
  const RunResult r = Run(DemoArgs() + " --prior-sigma 0.1");
  EXPECT_NE(r.exit_code, 0) << Explain(r);
  EXPECT_NE(r.exit_code, 3);
  EXPECT_THAT(r.err, HasSubstr("--prior"));
  const RunResult missing = Run(DemoArgs() + " --prior " + Quote(Path("none.yaml")));
  EXPECT_EQ(missing.exit_code, 1) << Explain(missing);
  EXPECT_THAT(missing.err, HasSubstr("rigcal solve: " + Path("none.yaml")));
}

// Options without effect together are usage errors (2) naming both options.
TEST_F(SolveCommandTest, IneffectiveOptionCombinationsAreUsageErrors) {
  WriteDemoDrive();
  for (const char* given : {"--pairs start", "--method lls", "--scale fixed"}) {
    const std::string option = given;
    const RunResult r = Run(DemoArgs() + " --online " + option);
    EXPECT_EQ(r.exit_code, 2) << option << ": " << Explain(r);
    const std::string name = option.substr(0, option.find(' '));
    EXPECT_THAT(r.err, HasSubstr(name + " excludes --online")) << Explain(r);
  }
  const RunResult every = Run(DemoArgs() + " --report-every 5");
  EXPECT_EQ(every.exit_code, 2) << Explain(every);
  EXPECT_THAT(every.err, HasSubstr("--report-every requires --online")) << Explain(every);
}

TEST_F(SolveCommandTest, HelpExplainsOptionsAndExitCodes) {
  const RunResult r = Run("solve --help");
  EXPECT_EQ(r.exit_code, 0) << Explain(r);
  for (const char* expected : {"--master",
                               "--slave",
                               "--method",
                               "--motion",
                               "--scale",
                               "partitions:N",
                               "--pairs",
                               "relative:STEP",
                               "--tolerance-ms",
                               "--truth",
                               "--truth-unit",
                               "metric",
                               "--prior",
                               "--prior-sigma",
                               "planar",
                               "--out",
                               "--json",
                               "--camchain",
                               "TUM",
                               "EuRoC",
                               "rigcal poses",
                               "slave odometry units",
                               "Exit status",
                               "3 the solve ran"}) {
    EXPECT_THAT(r.out, HasSubstr(expected));
  }
}

TEST_F(SolveCommandTest, InvalidOptionValuesAreRejected) {
  WriteDemoDrive();
  for (const char* bad :
       {"--scale partitions:0", "--scale fixd", "--pairs relative:", "--method gn",
        "--motion rotational", "--tolerance-ms -1", "--prior-sigma -1"}) {
    const RunResult r = Run(DemoArgs() + " " + bad);
    EXPECT_NE(r.exit_code, 0) << bad << "\n" << Explain(r);
    EXPECT_NE(r.exit_code, 3) << bad;
    EXPECT_EQ(r.out.find("master:"), std::string::npos) << bad << ": ran the solve";
  }
}

}  // namespace
}  // namespace rigcal
