// SPDX-License-Identifier: Apache-2.0
// The target module on synthetic views: a camera of known intrinsics sees a chessboard from
// random poses; the corners are projected with OpenCV (the same convention the module uses)
// plus Gaussian pixel noise of sigma 0.1 px.
//
// Tolerances: the principal point trades against a small rotation of every board pose (a
// 1-px shift is a 0.13 deg turn), so with 20 views of this board it is determined to about
// 0.5 px, not to the focal length's sigma / sqrt(N M) * f / spread ~ 0.05 px: over 40 runs (20
// seeds, both models) the worst of fx, fy, cx, cy was 0.2-1.2 px off and the fisheye k1 up to
// 0.016. Hence, with noise: the parameters within 3 px and 0.05; what the camera does, the
// projection at the corners after the best rotation between the true and estimated camera
// frames, within 3 sigma = 0.3 px (measured at most 0.18 px over those 40 runs). Without noise
// the parameters must come back to 1e-3 px, where any error of the model or the convention (a
// half-pixel shift, a swapped axis, a wrong distortion sign) shows. The parameters' reported
// sigma is checked against their errors over 20 runs per model (ParameterSigmaIsHonest).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#pragma GCC diagnostic pop

#include "rigcal/io/camera_files.h"
#include "rigcal/io/kalibr_camchain.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/pattern/intrinsics.h"
#include "rigcal/pattern/metric_scale.h"
#include "rigcal/pattern/reference_calibration.h"
#include "rigcal/pattern/target_poses.h"
#include "rigcal/pattern/target_views.h"
#include "support/board_views.h"
#include "support/omni_views.h"
#include "support/temp_dir.h"

namespace rigcal::pattern {
namespace {

using camera::CameraSpec;

constexpr double kNoisePx = 0.1;

CameraSpec TrueCamera(CameraSpec::Model model) {
  return test_support::EurocLikeCamera("cam", model);
}

// The target's pose in the camera for view k: the board (9x6, 0.04 m squares) 0.5..0.9 m in
// front, tilted up to ~35 degrees, so that it fills a good part of the image.
Pose CamFromTarget(std::mt19937& rng) {
  std::uniform_real_distribution<double> tilt(-0.6, 0.6);
  std::uniform_real_distribution<double> shift(-0.12, 0.12);
  std::uniform_real_distribution<double> depth(0.5, 0.9);
  Pose p;
  // Drawn one by one, last first (RandomVector3's order, calib/synthetic.h): the order in which
  // the operands of * or a constructor's arguments are evaluated is unspecified.
  const double about_z = 0.3 * tilt(rng), about_y = tilt(rng), about_x = tilt(rng);
  p.q = Eigen::AngleAxisd(about_x, Eigen::Vector3d::UnitX()) *
        Eigen::AngleAxisd(about_y, Eigen::Vector3d::UnitY()) *
        Eigen::AngleAxisd(about_z, Eigen::Vector3d::UnitZ());
  // Board centre (0.16, 0.1) at (shift, shift, depth).
  const double cz = depth(rng), cy = shift(rng);
  const Eigen::Vector3d centre(shift(rng), cy, cz);
  p.C = centre - p.q * Eigen::Vector3d(0.16, 0.10, 0.0);
  return p;  // q, C: cam_from_target rotation and the target origin in the camera
}

pattern::TargetView Project(const CameraSpec& spec, const Pose& cam_from_target, std::mt19937& rng,
                            double noise_px, int64_t t_ns) {
  return test_support::ProjectBoard(spec, cam_from_target, rng, noise_px, t_ns,
                                    "view" + std::to_string(t_ns / 1000000000) + ".png");
}

pattern::CameraViews SyntheticViews(const CameraSpec& spec, int n, unsigned seed,
                                    double noise_px = kNoisePx) {
  std::mt19937 rng(seed);
  pattern::CameraViews views;
  views.camera = spec.name;
  views.width = spec.width;
  views.height = spec.height;
  for (int k = 0; k < n; ++k) {
    views.views.push_back(Project(spec, CamFromTarget(rng), rng, noise_px, (k + 1) * 1000000000LL));
  }
  return views;
}

// Parameters within `pixels` (fx, fy, cx, cy) and `k1` (the first distortion coefficient).
void ExpectIntrinsicsNear(const CameraSpec& estimate, const CameraSpec& truth, double pixels = 3.0,
                          double k1 = 0.05) {
  for (int i = 0; i < 4; ++i) {
    EXPECT_NEAR(estimate.intrinsics[i], truth.intrinsics[i], pixels) << "intrinsics[" << i << "]";
  }
  ASSERT_EQ(estimate.distortion.size(), 4u);
  EXPECT_NEAR(estimate.distortion[0], truth.distortion[0], k1);
}

// What the camera does: the projection at the corners after the best rotation between the two
// camera frames, within 3 sigma.
void ExpectProjectionNear(const CameraSpec& estimate, const CameraSpec& truth,
                          const pattern::CameraViews& views) {
  EXPECT_LT(test_support::AlignedRmsAtCorners(truth, estimate, views), 3.0 * kNoisePx);
}

TEST(Intrinsics, PinholeRadtanRecoveredAndOutlierViewRejected) {
  const CameraSpec truth = TrueCamera(CameraSpec::Model::kPinhole);
  pattern::CameraViews views = SyntheticViews(truth, 20, 7);
  // View 5: every corner 3 px off in a random direction: an outlier.
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> angle(0.0, 2 * M_PI);
  for (Eigen::Vector2d& p : views.views[5].pixels) {
    const double a = angle(rng);
    p += 3.0 * Eigen::Vector2d(std::cos(a), std::sin(a));
  }
  auto result = pattern::CalibrateIntrinsics(views, {});
  ASSERT_TRUE(result.ok()) << result.error();
  ExpectIntrinsicsNear(result->spec, truth);
  ExpectProjectionNear(result->spec, truth, views);
  EXPECT_EQ(result->views_rejected, 1);
  ASSERT_EQ(result->views.size(), 20u);
  EXPECT_TRUE(result->views[5].rejected);
  EXPECT_FALSE(result->views[5].used);
  EXPECT_EQ(result->views_used, 19);
  // RMS of the used views: the noise (2-D RMS of sigma per axis is sqrt(2) sigma).
  EXPECT_NEAR(result->rms_px, std::sqrt(2.0) * kNoisePx, 0.03);
  EXPECT_GT(result->views[5].rms_px, 2.0);
  EXPECT_NE(pattern::FormatIntrinsics(*result, true).find("rejected (outlier)"), std::string::npos);
}

TEST(Intrinsics, EquidistantFisheyeRecovered) {
  const CameraSpec truth = TrueCamera(CameraSpec::Model::kFisheye);
  const pattern::CameraViews views = SyntheticViews(truth, 20, 11);
  pattern::IntrinsicsOptions options;
  options.model = CameraSpec::Model::kFisheye;
  auto result = pattern::CalibrateIntrinsics(views, options);
  ASSERT_TRUE(result.ok()) << result.error();
  EXPECT_EQ(result->spec.model, CameraSpec::Model::kFisheye);
  ExpectIntrinsicsNear(result->spec, truth);
  ExpectProjectionNear(result->spec, truth, views);
  EXPECT_EQ(result->views_rejected, 0);
}

TEST(Intrinsics, NoiselessViewsGiveTheExactCameraAndAreAllKept) {
  // Every view fits to the solver's rounding: their RMS spread is no reason to reject one, and
  // the parameters come back exactly.
  for (const CameraSpec::Model model : {CameraSpec::Model::kPinhole, CameraSpec::Model::kFisheye}) {
    const CameraSpec truth = TrueCamera(model);
    const pattern::CameraViews views = SyntheticViews(truth, 20, 5, /*noise_px=*/0.0);
    pattern::IntrinsicsOptions options;
    options.model = model;
    auto result = pattern::CalibrateIntrinsics(views, options);
    ASSERT_TRUE(result.ok()) << result.error();
    EXPECT_EQ(result->views_rejected, 0);
    EXPECT_EQ(result->views_used, 20);
    EXPECT_LT(result->rms_px, 1e-3);
    ExpectIntrinsicsNear(result->spec, truth, 1e-3, 1e-6);
  }
}

TEST(Intrinsics, ParameterSigmaIsHonest) {
  // Over 20 independent calibrations per model, the errors of all 8 parameters divided by their
  // reported sigma: RMS 1 for an honest sigma (the 8 of one run are correlated, so between 20
  // and 160 independent numbers: the RMS's spread is 0.06-0.16), [0.6, 1.6] fails for a sigma
  // wrong by more than half.
  for (const CameraSpec::Model model : {CameraSpec::Model::kPinhole, CameraSpec::Model::kFisheye}) {
    const CameraSpec truth = TrueCamera(model);
    std::vector<double> truth_params(truth.intrinsics.begin(), truth.intrinsics.end());
    truth_params.insert(truth_params.end(), truth.distortion.begin(), truth.distortion.end());
    double sum_sq = 0.0;
    int count = 0;
    for (unsigned seed = 1; seed <= 20; ++seed) {
      const pattern::CameraViews views = SyntheticViews(truth, 20, seed);
      pattern::IntrinsicsOptions options;
      options.model = model;
      auto result = pattern::CalibrateIntrinsics(views, options);
      ASSERT_TRUE(result.ok()) << result.error();
      ASSERT_EQ(result->parameter_std.size(), 8u) << result->parameter_std_error;
      ASSERT_EQ(result->parameter_names.size(), 8u);
      std::vector<double> estimate(result->spec.intrinsics.begin(), result->spec.intrinsics.end());
      estimate.insert(estimate.end(), result->spec.distortion.begin(),
                      result->spec.distortion.end());
      for (size_t i = 0; i < 8; ++i) {
        ASSERT_GT(result->parameter_std[i], 0.0) << result->parameter_names[i];
        const double z = (estimate[i] - truth_params[i]) / result->parameter_std[i];
        EXPECT_LT(std::abs(z), 5.0) << result->parameter_names[i] << " seed " << seed;
        sum_sq += z * z;
        ++count;
      }
    }
    const double rms = std::sqrt(sum_sq / count);
    std::printf("%s: normalised parameter error RMS %.2f over %d\n",
                std::string(camera::ModelName(model)).c_str(), rms, count);
    EXPECT_GT(rms, 0.6);
    EXPECT_LT(rms, 1.6);
  }
  // The pinhole sigma against OpenCV's (same least squares, other code): the same covariance up
  // to its scale, which OpenCV takes as the residuals' sum of squares over corners - unknowns
  // where there are 2 residuals per corner (too large by about sqrt(2); the runs above show
  // ours honest): ours / OpenCV's = sqrt((N - P) / (2 N - P)) for every parameter.
  const CameraSpec truth = TrueCamera(CameraSpec::Model::kPinhole);
  const pattern::CameraViews views = SyntheticViews(truth, 20, 3);
  auto result = pattern::CalibrateIntrinsics(views, {});
  ASSERT_TRUE(result.ok()) << result.error();
  ASSERT_EQ(result->parameter_std.size(), 8u);
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> image;
  for (const pattern::TargetView& v : views.views) {
    object.emplace_back();
    image.emplace_back();
    for (size_t j = 0; j < v.pixels.size(); ++j) {
      object.back().emplace_back(v.target_points[j].x(), v.target_points[j].y(), 0.0F);
      image.back().emplace_back(v.pixels[j].x(), v.pixels[j].y());
    }
  }
  cv::Mat K;
  cv::Mat D;
  cv::Mat std_intrinsics;
  cv::Mat std_extrinsics;
  cv::Mat per_view;
  std::vector<cv::Mat> rvecs;
  std::vector<cv::Mat> tvecs;
  cv::calibrateCamera(
      object, image, cv::Size(truth.width, truth.height), K, D, rvecs, tvecs, std_intrinsics,
      std_extrinsics, per_view, cv::CALIB_FIX_K3,
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));
  double corners = 0.0;
  for (const pattern::TargetView& v : views.views) corners += static_cast<double>(v.pixels.size());
  const double unknowns = 8.0 + 6.0 * static_cast<double>(views.views.size());
  const double ratio = std::sqrt((corners - unknowns) / (2.0 * corners - unknowns));
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(result->parameter_std[static_cast<size_t>(i)] / std_intrinsics.at<double>(i), ratio,
                1e-3 * ratio)
        << result->parameter_names[static_cast<size_t>(i)];
  }
}

TEST(Intrinsics, TooFewViewsIsAnError) {
  const pattern::CameraViews views = SyntheticViews(TrueCamera(CameraSpec::Model::kPinhole), 2, 3);
  auto result = pattern::CalibrateIntrinsics(views, {});
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.error().find("2 views with a target, need at least 4"), std::string::npos)
      << result.error();
}

TEST(TargetPoses, PnpRecoversThePosesAndTheGlobalReferenceTheRig) {
  // A two-camera rig: cam1 0.11 m to the right of cam0, turned 3 degrees about y. Both see the
  // board at every instant; their target poses give the rig back.
  const CameraSpec spec = TrueCamera(CameraSpec::Model::kPinhole);
  Similarity cam0_from_cam1;
  cam0_from_cam1.q = Eigen::AngleAxisd(3.0 * M_PI / 180, Eigen::Vector3d::UnitY());
  cam0_from_cam1.C = Eigen::Vector3d(0.11, 0.001, -0.002);
  std::mt19937 rng(5);
  pattern::CameraViews views0;
  pattern::CameraViews views1;
  for (pattern::CameraViews* v : {&views0, &views1}) {
    v->width = spec.width;
    v->height = spec.height;
  }
  views0.camera = "cam0";
  views1.camera = "cam1";
  for (int k = 0; k < 15; ++k) {
    const Pose cam0_from_target = CamFromTarget(rng);
    // cam1_from_target = inv(cam0_from_cam1) * cam0_from_target
    Pose cam1_from_target;
    cam1_from_target.q = cam0_from_cam1.q.conjugate() * cam0_from_target.q;
    cam1_from_target.C = cam0_from_cam1.q.conjugate() * (cam0_from_target.C - cam0_from_cam1.C);
    views0.views.push_back(Project(spec, cam0_from_target, rng, 0.0, (k + 1) * 1000000000LL));
    views1.views.push_back(Project(spec, cam1_from_target, rng, 0.0, (k + 1) * 1000000000LL));
  }
  auto poses0 = pattern::EstimateTargetPoses(views0, spec);
  auto poses1 = pattern::EstimateTargetPoses(views1, spec);
  ASSERT_TRUE(poses0.ok()) << poses0.error();
  ASSERT_TRUE(poses1.ok()) << poses1.error();
  for (const pattern::ViewStatistics& v : *poses0) EXPECT_LT(v.rms_px, 1e-6);
  const TimedTrajectory t0 = pattern::PosesAsTrajectory("cam0", *poses0, 2.0);
  const TimedTrajectory t1 = pattern::PosesAsTrajectory("cam1", *poses1, 2.0);
  ASSERT_EQ(t0.size(), 15u);
  auto reference = pattern::EstimateGlobalReference(t0, t1, 1000);
  ASSERT_TRUE(reference.ok()) << reference.error();
  EXPECT_LT(reference->master_from_slave.q.angularDistance(cam0_from_cam1.q), 1e-7);
  EXPECT_LT((reference->master_from_slave.C - cam0_from_cam1.C).norm(), 1e-7);
  EXPECT_EQ(reference->instants, 15);
  double rms = 0.0;
  auto stereo = pattern::EstimateStereoReference(views0, spec, views1, spec, &rms);
  ASSERT_TRUE(stereo.ok()) << stereo.error();
  EXPECT_LT(stereo->master_from_slave.q.angularDistance(cam0_from_cam1.q), 1e-6);
  EXPECT_LT((stereo->master_from_slave.C - cam0_from_cam1.C).norm(), 1e-6);

  // lambda_world: the master's target poses against its odometry in another unit (positions
  // divided by 0.37 and moved, rotated frame): the fit gives 0.37 metres per unit.
  TimedTrajectory odometry = pattern::CameraLocal(t0);
  for (Pose& p : odometry.poses) p.C /= 0.37;
  auto scale = pattern::EstimateWorldScale(odometry, t0, 1000);
  ASSERT_TRUE(scale.ok()) << scale.error();
  EXPECT_NEAR(scale->metres_per_unit, 0.37, 1e-9);
  EXPECT_LT(scale->fit_rms_m, 1e-9);
  EXPECT_NE(scale->message.find("metres"), std::string::npos);

  // Too few shared instants.
  TimedTrajectory short1 = t1;
  short1.t_ns.resize(2);
  short1.poses.resize(2);
  auto failed = pattern::EstimateGlobalReference(t0, short1, 1000);
  ASSERT_FALSE(failed.ok());
  EXPECT_NE(failed.error().find("2 instants"), std::string::npos) << failed.error();
}

TEST(KalibrCamchain, WrittenCompleteAndReadBack) {
  const auto dir = support::FreshTempDir("target_camchain");
  io::CamchainEntry cam0;
  cam0.spec = TrueCamera(CameraSpec::Model::kPinhole);
  cam0.spec.name = "left";
  io::CamchainEntry cam1;
  cam1.spec = TrueCamera(CameraSpec::Model::kFisheye);
  cam1.spec.name = "right";
  Similarity cam0_from_cam1;
  cam0_from_cam1.q = Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 2, 3).normalized());
  cam0_from_cam1.C = Eigen::Vector3d(0.11, -0.02, 0.03);
  cam1.cam0_from_cam = cam0_from_cam1;
  const std::string path = (dir / "camchain.yaml").string();
  ASSERT_TRUE(io::WriteKalibrCamchain(path, {cam0, cam1}, "test").ok());

  auto specs = io::ReadKalibrIntrinsics(path);
  ASSERT_TRUE(specs.ok()) << specs.error();
  ASSERT_EQ(specs->size(), 2u);
  EXPECT_EQ((*specs)[0].name, "left");
  EXPECT_EQ((*specs)[1].model, CameraSpec::Model::kFisheye);
  EXPECT_EQ((*specs)[0].width, 752);
  EXPECT_EQ((*specs)[0].intrinsics, cam0.spec.intrinsics);
  EXPECT_EQ((*specs)[1].distortion, cam1.spec.distortion);
  auto chain = io::ReadCamchain(path);
  ASSERT_TRUE(chain.ok()) << chain.error();
  ASSERT_EQ(chain->size(), 2u);
  // T_cn_cnm1 of cam1 maps cam0 points to cam1: p1 = R^T (p0 - C).
  const Eigen::Matrix4d T = (*chain)[1].cn_from_cnm1;
  const Eigen::Vector3d p0(0.3, -0.2, 1.5);
  const Eigen::Vector3d p1 = cam0_from_cam1.q.conjugate() * (p0 - cam0_from_cam1.C);
  EXPECT_LT((T.topLeftCorner<3, 3>() * p0 + T.topRightCorner<3, 1>() - p1).norm(), 1e-12);

  io::CamchainEntry missing = cam1;
  missing.cam0_from_cam.reset();
  const Status s = io::WriteKalibrCamchain(path, {cam0, missing}, "");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("right: no extrinsics"), std::string::npos) << s.message();
}

TEST(TargetViews, BadImagesGiveClearErrors) {
  const auto dir = support::FreshTempDir("target_views");
  pattern::ChessboardSpec board;
  // Blank images: no chessboard anywhere.
  std::filesystem::create_directories(dir / "blank");
  cv::imwrite((dir / "blank" / "a01.png").string(), cv::Mat(120, 160, CV_8UC1, cv::Scalar(128)));
  cv::imwrite((dir / "blank" / "a02.png").string(), cv::Mat(120, 160, CV_8UC1, cv::Scalar(90)));
  auto none = pattern::DetectChessboardViews("cam", (dir / "blank").string(), board);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().find("no 9x6 chessboard (inner corners) found in any of the 2 images"),
            std::string::npos)
      << none.error();
  // Mixed resolutions.
  std::filesystem::create_directories(dir / "mixed");
  cv::imwrite((dir / "mixed" / "a01.png").string(), cv::Mat(120, 160, CV_8UC1, cv::Scalar(0)));
  cv::imwrite((dir / "mixed" / "a02.png").string(), cv::Mat(100, 160, CV_8UC1, cv::Scalar(0)));
  auto mixed = pattern::DetectChessboardViews("cam", (dir / "mixed").string(), board);
  ASSERT_FALSE(mixed.ok());
  EXPECT_NE(mixed.error().find("mixed resolutions: a01.png is 160x120, a02.png is 160x100"),
            std::string::npos)
      << mixed.error();
  // An empty folder, a missing one.
  std::filesystem::create_directories(dir / "empty");
  EXPECT_FALSE(pattern::DetectChessboardViews("cam", (dir / "empty").string(), board).ok());
  auto missing = pattern::LoadCameraViews("cam", (dir / "nothing").string(), board, 0, 0);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("is not a folder"), std::string::npos) << missing.error();
  // A malformed detection CSV names file and line.
  std::filesystem::create_directories(dir / "csv");
  {
    std::ofstream out(dir / "csv" / "1403709385000000000.csv");
    out << "#ts,tag_rows,tag_cols,tag_size,tag_spacing,kp_x,kp_y,p_x,p_y,p_z,tag_id,corner_idx\n"
        << "1403709385000000000,6,6,0.088,0.3,10,20,0,0,0,0,0\n"
        << "1403709385000000000,6,6,0.088,0.3,10,x,0,0,0,0,1\n";
  }
  auto csv = pattern::LoadCameraViews("cam", (dir / "csv").string(), board, 752, 480);
  ASSERT_FALSE(csv.ok());
  EXPECT_NE(csv.error().find("1403709385000000000.csv:3: expected 12 numbers"), std::string::npos)
      << csv.error();
  auto no_resolution = pattern::LoadCameraViews("cam", (dir / "csv").string(), board, 0, 0);
  ASSERT_FALSE(no_resolution.ok());
  EXPECT_NE(no_resolution.error().find("--resolution"), std::string::npos);
}

}  // namespace
}  // namespace rigcal::pattern
