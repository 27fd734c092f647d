// SPDX-License-Identifier: Apache-2.0
// Real data: the EuRoC "imu_april" calibration sequence (stereo cam0/cam1, 20 Hz, 72 s, full
// 6-DoF hand-held motion in front of an AprilGrid). Each camera's poses come from its own PnP
// on the grid (support/euroc_aprilgrid.h); cam1's positions are then scaled by an arbitrary
// factor to play a monocular odometry with its own unit. The calibrator must recover
// T_cam0_cam1 of the EuRoC calibration and the scale 1 / factor.
//
// Environment:
//   RIGCAL_EUROC_TUM_OUT=<dir>  also write cam0.txt, cam1.txt (TUM) and truth.yaml there, for
//                               `rigcal solve --master cam0.txt --slave cam1.txt --truth ...`.

#include "support/euroc_aprilgrid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/base/types.h"
#include "rigcal/io/trajectory_io.h"
#include "support/opencv_handeye.h"
#include "support/skip.h"

#if defined(RIGCAL_BINARY) && __has_include(<nlohmann/json.hpp>)
#include <nlohmann/json.hpp>
#define RIGCAL_EUROC_RUN_SOLVE 1
#endif

namespace rigcal {
namespace {

namespace fs = std::filesystem;

// Arbitrary odometry unit of cam1: its positions are multiplied by this, so the similarity
// cam0_from_cam1 has scale 1 / kCam1Unit.
constexpr double kCam1Unit = 2.7;

// Accuracy targets (the lead's specification for this data set). For scale: the per-frame PnP
// noise (median reprojection 0.4 px at ~1 m with f = 458 px: ~1 mm / 0.05 deg per pose) over
// ~1400 frames and translations of ~1 m supports well below 0.1 % on the scale, so 0.3 % is a
// target with margin, not a noise floor. The OpenCV reference on the same (metric) poses is
// ~0.25 deg / ~6.8 mm: the targets ask for clearly better.
constexpr double kMaxRotDeg = 0.15;
constexpr double kMaxTransMm = 2.5;
constexpr double kMaxScalePct = 0.3;

// OpenCV builds all O(K^2) pairs; every 3rd frame (~470 poses, ~110k pairs) takes ~13 s for
// the five methods and gives its best figures on this data (every frame: worse and ~minutes).
#if defined(__SANITIZE_ADDRESS__) || defined(RIGCAL_ASAN)
constexpr int kOpenCvStride = 10;
#else
constexpr int kOpenCvStride = 3;
#endif

class EurocAprilGridTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string reason;
    if (!support::EurocAprilGridAvailable(&reason)) {
      skip_reason_ = new std::string(reason);
      return;
    }
    auto rig = support::LoadEurocAprilGridRig();
    if (!rig) {
      load_error_ = new std::string(rig.error());
      return;
    }
    rig_ = new support::EurocRig(std::move(*rig));
  }
  static void TearDownTestSuite() {
    delete rig_;
    delete skip_reason_;
    delete load_error_;
    rig_ = nullptr;
    skip_reason_ = nullptr;
    load_error_ = nullptr;
  }
  void SetUp() override {
    if (skip_reason_ != nullptr) RIGCAL_SKIP_MISSING() << *skip_reason_;
    ASSERT_EQ(load_error_, nullptr) << *load_error_;
    ASSERT_NE(rig_, nullptr);
  }

  // The recording with cam1 in its own unit, and the truth for it.
  static RigRecording ScaledRecording() {
    RigRecording rec = rig_->recording;
    support::ScalePositions(&rec.slaves[0], kCam1Unit);
    return rec;
  }
  static Similarity ScaledTruth() {
    Similarity t = rig_->truth;
    t.scale = 1.0 / kCam1Unit;
    return t;
  }

  static support::EurocRig* rig_;
  static std::string* skip_reason_;
  static std::string* load_error_;
};

support::EurocRig* EurocAprilGridTest::rig_ = nullptr;
std::string* EurocAprilGridTest::skip_reason_ = nullptr;
std::string* EurocAprilGridTest::load_error_ = nullptr;

std::string FormatError(const CalibrationError& e) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(4) << "rot " << e.rot_deg << " deg, trans "
      << std::setprecision(3) << e.trans_err * 1000.0 << " mm, scale " << std::setprecision(4)
      << e.scale_pct << " %";
  return out.str();
}

// Per-frame consistency of the two cameras' PnP poses with the ground truth: the residual
// (T_cam0^k X)^-1 T_cam1^k of every frame (identity for perfect poses), averaged. Its mean is the
// error of the naive per-frame stereo estimate (~0.19 deg / ~3.4 mm here), its spread the noise
// of the poses: context for the accuracy targets, printed when they are missed. (A joint stereo
// bundle adjustment of the same corners, cv::stereoCalibrate with fixed intrinsics on every 10th
// frame, lands 0.03 deg / 0.3 mm from the ground truth: data and truth are consistent, the error
// is in the single-view PnP poses.)
struct PnpConsistency {
  double mean_rot_deg = 0.0;  // |mean rotation vector|
  double rms_rot_deg = 0.0;
  double mean_trans_mm = 0.0;  // |mean C|
  Eigen::Vector3d std_trans_mm = Eigen::Vector3d::Zero();
};

PnpConsistency Consistency(const RigRecording& metric, const Similarity& truth) {
  Pose x;
  x.q = truth.q;
  x.C = truth.C;
  Eigen::Vector3d rot_sum = Eigen::Vector3d::Zero(), c_sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d c_sq = Eigen::Vector3d::Zero();
  double rot_sq = 0.0;
  const double n = static_cast<double>(metric.size());
  for (size_t k = 0; k < metric.size(); ++k) {
    const Pose r = (metric.master.poses[k] * x).Between(metric.slaves[0].poses[k]);
    const Eigen::AngleAxisd aa(r.q);
    const Eigen::Vector3d rv = aa.axis() * aa.angle() * kDegPerRad;
    rot_sum += rv;
    rot_sq += rv.squaredNorm();
    c_sum += r.C * 1000.0;
    c_sq += (r.C * 1000.0).cwiseAbs2();
  }
  PnpConsistency c;
  c.mean_rot_deg = (rot_sum / n).norm();
  c.rms_rot_deg = std::sqrt(rot_sq / n);
  c.mean_trans_mm = (c_sum / n).norm();
  c.std_trans_mm = (c_sq / n - (c_sum / n).cwiseAbs2()).cwiseSqrt();
  return c;
}

std::string FormatConsistency(const PnpConsistency& c) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "per-frame PnP pose pair vs ground truth: mean "
      << c.mean_rot_deg << " deg / " << c.mean_trans_mm << " mm, spread " << c.rms_rot_deg
      << " deg rms / (" << c.std_trans_mm.transpose() << ") mm std";
  return out.str();
}

// The data and PnP are what README-provenance.txt describes (guards the support code): ~1416
// frames with detections per camera, median reprojection ~0.4-0.5 px.
TEST_F(EurocAprilGridTest, PnpPosesMatchProvenance) {
  std::cout << "PnP cam0: " << rig_->cam0_stats.accepted << "/" << rig_->cam0_stats.frames
            << " frames, median reprojection " << rig_->cam0_stats.median_reproj_px << " px\n"
            << "PnP cam1: " << rig_->cam1_stats.accepted << "/" << rig_->cam1_stats.frames
            << " frames, median reprojection " << rig_->cam1_stats.median_reproj_px << " px\n"
            << "frames with both poses: " << rig_->recording.size() << "\n";
  EXPECT_EQ(rig_->cam0_stats.frames, 1439);
  EXPECT_GT(rig_->cam0_stats.accepted, 1400);
  EXPECT_GT(rig_->cam1_stats.accepted, 1400);
  EXPECT_GT(rig_->recording.size(), 1400u);
  EXPECT_LT(rig_->cam0_stats.median_reproj_px, 0.6);
  EXPECT_LT(rig_->cam1_stats.median_reproj_px, 0.6);
  EXPECT_TRUE(rig_->recording.Check().ok()) << rig_->recording.Check().message();
  // Overlapping stereo: the per-frame relative pose cam0 -> cam1 is the extrinsic up to PnP
  // errors (provenance: naive per-frame stereo PnP is within ~0.16 deg / ~3 mm; measured here
  // ~0.19 deg / ~3.3 mm mean, ~0.7 deg rms). A wrong PnP frame convention (cam_from_target
  // instead of target_from_cam) or a wrong intrinsic would be off by degrees / centimetres.
  const PnpConsistency c = Consistency(rig_->recording, rig_->truth);
  std::cout << FormatConsistency(c) << "\n";
  EXPECT_LT(c.mean_rot_deg, 0.5);
  EXPECT_LT(c.mean_trans_mm, 10.0);
  EXPECT_LT(c.rms_rot_deg, 2.0);
}

TEST_F(EurocAprilGridTest, CalibrateRigDefaultOptionsMeetsTargets) {
  const RigRecording rec = ScaledRecording();
  const Similarity truth = ScaledTruth();

  // OpenCV's best on the metric poses (it cannot handle the scaled ones), for reference.
  std::vector<Pose> master, slave;
  support::SubsampledPoses(rig_->recording, 0, kOpenCvStride, &master, &slave);
  CalibrationError best_cv;
  best_cv.rot_deg = best_cv.trans_err = 1e9;
  std::string best_rot_method, best_trans_method;
  for (const auto& he : support::OpenCvHandEyeAll(master, slave)) {
    if (!he.ok) {
      std::cout << "OpenCV " << ToString(he.method) << " failed: " << he.error << "\n";
      continue;
    }
    const CalibrationError e = CompareToTruth(he.master_from_slave, rig_->truth);
    std::cout << "OpenCV " << std::left << std::setw(10) << ToString(he.method) << std::right
              << " (metric poses, every " << kOpenCvStride << ". frame, " << master.size()
              << " poses): " << FormatError(e) << "\n";
    if (e.rot_deg < best_cv.rot_deg) {
      best_cv.rot_deg = e.rot_deg;
      best_rot_method = ToString(he.method);
    }
    if (e.trans_err < best_cv.trans_err) {
      best_cv.trans_err = e.trans_err;
      best_trans_method = ToString(he.method);
    }
  }
  std::cout << "OpenCV best: rot " << best_cv.rot_deg << " deg (" << best_rot_method << "), trans "
            << best_cv.trans_err * 1000.0 << " mm (" << best_trans_method << ")\n";
  RecordProperty("opencv_best_rot_deg", std::to_string(best_cv.rot_deg));
  RecordProperty("opencv_best_trans_mm", std::to_string(best_cv.trans_err * 1000.0));

  const CalibrationOptions options;  // defaults
  const RigCalibration result = CalibrateRig(rec, options);
  std::cout << result.BriefReport() << "\n";
  ASSERT_EQ(result.slaves.size(), 1u);
  const SlaveCalibration& s = result.slaves[0];
  ASSERT_TRUE(s.usable()) << ToString(s.termination) << ": " << s.message;
  const CalibrationError e = CompareToTruth(s.estimate, truth);
  std::cout << "rigcal default (cam1 x " << kCam1Unit << "): " << FormatError(e) << "  [scale "
            << s.estimate.scale << ", truth " << truth.scale << "; " << s.motions.used
            << " motions used of " << s.motions.total << ", " << result.pairs_selected
            << " pairs]\n";
  RecordProperty("rigcal_rot_deg", std::to_string(e.rot_deg));
  RecordProperty("rigcal_trans_mm", std::to_string(e.trans_err * 1000.0));
  RecordProperty("rigcal_scale_pct", std::to_string(e.scale_pct));

  const std::string floor = FormatConsistency(Consistency(rig_->recording, rig_->truth));
  EXPECT_LE(e.rot_deg, kMaxRotDeg) << floor;
  EXPECT_LE(e.trans_err * 1000.0, kMaxTransMm) << floor;
  EXPECT_LE(e.scale_pct, kMaxScalePct);
  EXPECT_EQ(s.motion_model, MotionModel::kGeneral);
}

// Writes the TUM files and truth for `rigcal solve` (test temp dir, and RIGCAL_EUROC_TUM_OUT
// when set), then runs the rigcal binary on them when the build provides it.
TEST_F(EurocAprilGridTest, RigcalSolveOnTumFiles) {
  const RigRecording rec = ScaledRecording();
  const Similarity truth = ScaledTruth();
  auto write_all = [&](const fs::path& dir) {
    std::error_code ec;
    fs::create_directories(dir, ec);
    ASSERT_FALSE(ec) << dir << ": " << ec.message();
    std::string error;
    ASSERT_TRUE(
        support::WriteTumTrajectory((dir / "cam0.txt").string(), rec.t_ns, rec.master, &error))
        << error;
    ASSERT_TRUE(
        support::WriteTumTrajectory((dir / "cam1.txt").string(), rec.t_ns, rec.slaves[0], &error))
        << error;
    ASSERT_TRUE(support::WriteTruthYaml((dir / "truth.yaml").string(), "cam1", truth, &error))
        << error;
  };
  if (const char* out = std::getenv("RIGCAL_EUROC_TUM_OUT"); out != nullptr && *out != '\0') {
    write_all(out);
    if (HasFatalFailure()) return;
    std::cout << "wrote cam0.txt, cam1.txt, truth.yaml to " << out << "\n";
  }
  const fs::path dir = fs::path(::testing::TempDir()) / "rigcal_euroc_aprilgrid";
  write_all(dir);
  if (HasFatalFailure()) return;

  // The files read back through the project's trajectory reader (format detection, exact
  // stamps, poses to the printed precision).
  for (const auto& [file, track] :
       {std::pair{"cam0.txt", &rec.master}, std::pair{"cam1.txt", &rec.slaves[0]}}) {
    io::TrajectoryFormat format = io::TrajectoryFormat::kNative;
    auto read = io::ReadTrajectory((dir / file).string(), {}, &format);
    ASSERT_TRUE(read.ok()) << read.error();
    EXPECT_EQ(format, io::TrajectoryFormat::kTum);
    EXPECT_EQ(read->name, track->name);
    ASSERT_EQ(read->t_ns, rec.t_ns);
    for (size_t k = 0; k < read->size(); ++k) {
      ASSERT_LT((read->poses[k].C - track->poses[k].C).norm(), 1e-12) << file << " line " << k;
      ASSERT_LT(read->poses[k].q.angularDistance(track->poses[k].q), 1e-12) << file << " " << k;
    }
  }

#if defined(RIGCAL_EUROC_RUN_SOLVE)
  const fs::path binary = RIGCAL_BINARY;
  if (!fs::exists(binary)) RIGCAL_SKIP_MISSING() << "rigcal binary not built: " << binary;
  const fs::path log = dir / "solve.stderr";
  const std::string cmd = "'" + binary.string() + "' solve --master '" +
                          (dir / "cam0.txt").string() + "' --slave '" +
                          (dir / "cam1.txt").string() + "' --truth '" +
                          (dir / "truth.yaml").string() + "' --json 2>'" + log.string() + "'";
  FILE* pipe = popen(cmd.c_str(), "r");
  ASSERT_NE(pipe, nullptr) << cmd;
  std::string stdout_text;
  char buf[4096];
  size_t n = 0;
  while ((n = fread(buf, 1, sizeof(buf), pipe)) > 0) stdout_text.append(buf, n);
  const int status = pclose(pipe);
  std::ifstream log_in(log);
  const std::string stderr_text((std::istreambuf_iterator<char>(log_in)),
                                std::istreambuf_iterator<char>());
  ASSERT_EQ(status, 0) << cmd << "\nstdout:\n" << stdout_text << "\nstderr:\n" << stderr_text;

  const auto json = nlohmann::json::parse(stdout_text, nullptr, /*allow_exceptions=*/false);
  ASSERT_FALSE(json.is_discarded()) << "not JSON:\n" << stdout_text;
  ASSERT_TRUE(json.contains("slaves") && json["slaves"].is_array() && json["slaves"].size() == 1)
      << json.dump(2);
  const auto& slave = json["slaves"][0];
  ASSERT_TRUE(slave.contains("errors")) << json.dump(2);
  const auto& errors = slave["errors"];
  const double rot_deg = errors.at("rot_deg").get<double>();
  const double trans_mm = errors.at("trans_err").get<double>() * 1000.0;
  const double scale_pct = errors.at("scale_pct").get<double>();
  std::cout << "rigcal solve (TUM files): rot " << rot_deg << " deg, trans " << trans_mm
            << " mm, scale " << scale_pct << " %\n";
  EXPECT_EQ(slave.value("name", ""), "cam1");
  EXPECT_EQ(slave.value("termination", ""), "solved");
  EXPECT_EQ(slave.value("state", ""), "converged");
  // The accuracy targets are asserted on the library call (CalibrateRigDefaultOptionsMeetsTargets);
  // here the command path must work: errors within ~2-3x of OpenCV's reference on the metric
  // poses (0.25 deg / 6.8 mm), and the scale found (an unscaled answer would be 170 % off).
  EXPECT_LE(rot_deg, 0.75);
  EXPECT_LE(trans_mm, 20.0);
  EXPECT_LE(scale_pct, 2.0);

  // The command must agree with the library call on the same poses (the TUM round trip keeps
  // 17 significant digits, so only the solver's own tolerance remains).
  const RigCalibration lib = CalibrateRig(rec, CalibrationOptions{});
  ASSERT_EQ(lib.slaves.size(), 1u);
  const CalibrationError e = CompareToTruth(lib.slaves[0].estimate, truth);
  EXPECT_NEAR(rot_deg, e.rot_deg, 1e-3);
  EXPECT_NEAR(trans_mm, e.trans_err * 1000.0, 1e-2);
  EXPECT_NEAR(scale_pct, e.scale_pct, 1e-3);
#else
  std::cout << "rigcal binary not available to this test (RIGCAL_BINARY not defined); only "
               "the TUM files were written to "
            << dir << "\n";
#endif
}

}  // namespace
}  // namespace rigcal
