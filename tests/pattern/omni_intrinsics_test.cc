// SPDX-License-Identifier: Apache-2.0
// The omnidirectional (unified / Mei) model through cv::omnidir on simulated views: a wide
// camera (xi 0.8, fu 650 px) sees a 9x6 chessboard from 24 poses;
// corners projected with cv::omnidir::projectPoints plus 0.1 px Gaussian noise.
//
// Tolerances from the math: xi and the focal lengths are strongly correlated (near the centre
// only f / (1 + xi) is seen), so the test scores what a user gets, the projection: the
// estimated model projects bearings over the whole image within 0.5 px of the true one. With
// 24 x 54 corners at 0.1 px the projection's error is about 0.1 px where the board was seen and
// a few tenths at the far edge of the image (measured 0.26 px); a wrong
// convention (swapped axes, a distortion sign, the model's xi) moves it by pixels. The fit's
// RMS is the noise's 2-D RMS, 0.1 * sqrt(2) = 0.141 px (< 0.15 tested; measured 0.136).

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/ccalib/omnidir.hpp>
#pragma GCC diagnostic pop

#include "rigcal/io/kalibr_camchain.h"
#include "rigcal/pattern/omni_intrinsics.h"
#include "support/temp_dir.h"

namespace rigcal::pattern {
namespace {

struct TrueOmni {
  cv::Matx33d K{650.0, 0.0, 376.0, 0.0, 648.0, 240.0, 0.0, 0.0, 1.0};
  double xi = 0.8;
  cv::Vec4d D{-0.12, 0.03, 2e-4, -3e-4};
};

std::vector<cv::Point2d> Project(const TrueOmni& cam, const std::vector<cv::Point3d>& points,
                                 const cv::Vec3d& rvec, const cv::Vec3d& tvec) {
  std::vector<cv::Point2d> image;
  cv::omnidir::projectPoints(points, image, rvec, tvec, cam.K, cam.xi, cam.D);
  return image;
}

pattern::CameraViews SimulatedViews(const TrueOmni& cam, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> tilt(-0.7, 0.7);
  std::uniform_real_distribution<double> shift(-0.25, 0.25);
  std::uniform_real_distribution<double> depth(0.25, 0.45);
  std::normal_distribution<double> noise(0.0, 0.1);
  std::vector<cv::Point3d> board;
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 9; ++c) board.emplace_back(0.04 * c, 0.04 * r, 0.0);
  }
  pattern::CameraViews views;
  views.camera = "fish";
  views.width = 752;
  views.height = 480;
  while (static_cast<int>(views.views.size()) < n) {
    // Every vector drawn last component first (RandomVector3's order, calib/synthetic.h): the
    // order in which a constructor's arguments are evaluated is unspecified.
    const double rz = 0.3 * tilt(rng), ry = tilt(rng);
    const cv::Vec3d rvec(tilt(rng), ry, rz);
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    // Board centre (0.16, 0.10) at (shift, shift, depth).
    const double cz = depth(rng), cy = shift(rng);
    const cv::Vec3d centre(shift(rng), cy, cz);
    const cv::Vec3d tvec = centre - R * cv::Vec3d(0.16, 0.10, 0.0);
    const std::vector<cv::Point2d> image = Project(cam, board, rvec, tvec);
    bool inside = true;
    for (const cv::Point2d& p : image) {
      inside = inside && p.x > 5 && p.y > 5 && p.x < views.width - 5 && p.y < views.height - 5;
    }
    if (!inside) continue;
    pattern::TargetView view;
    view.t_ns = static_cast<int64_t>(views.views.size() + 1) * 1000000000LL;
    view.file = std::to_string(views.views.size());
    for (size_t j = 0; j < board.size(); ++j) {
      const double dy = noise(rng);
      view.pixels.emplace_back(image[j].x + noise(rng), image[j].y + dy);
      view.target_points.emplace_back(board[j].x, board[j].y, board[j].z);
    }
    views.views.push_back(std::move(view));
  }
  return views;
}

TEST(OmniIntrinsics, RecoversTheProjectionAndWritesKalibrOmni) {
  const TrueOmni truth;
  const pattern::CameraViews views = SimulatedViews(truth, 24, 5);
  auto omni = pattern::CalibrateOmni(views, 80);
  ASSERT_TRUE(omni.ok()) << omni.error();
  std::cout << pattern::FormatOmni(*omni);
  EXPECT_LT(omni->rms_px, 0.15);
  EXPECT_GE(omni->views_used, 20);
  // Bearings over the image: field angles 0..80 deg at 16 azimuths, those the true model
  // projects into the image, projected through both models.
  TrueOmni estimate;
  estimate.K = cv::Matx33d(omni->intrinsics[0], 0.0, omni->intrinsics[2], 0.0, omni->intrinsics[1],
                           omni->intrinsics[3], 0.0, 0.0, 1.0);
  estimate.xi = omni->xi;
  estimate.D =
      cv::Vec4d(omni->distortion[0], omni->distortion[1], omni->distortion[2], omni->distortion[3]);
  std::vector<cv::Point3d> all;
  for (int a = 0; a <= 80; a += 5) {
    for (int k = 0; k < 16; ++k) {
      const double theta = a * M_PI / 180.0;
      const double phi = k * M_PI / 8.0;
      all.emplace_back(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                       std::cos(theta));
    }
  }
  const std::vector<cv::Point2d> all_true = Project(truth, all, {0, 0, 0}, {0, 0, 0});
  std::vector<cv::Point3d> bearings;
  std::vector<cv::Point2d> back;
  for (size_t i = 0; i < all.size(); ++i) {
    const cv::Point2d& p = all_true[i];
    if (p.x < 0 || p.y < 0 || p.x > 751 || p.y > 479) continue;
    bearings.push_back(all[i]);
    back.push_back(p);
  }
  ASSERT_GT(bearings.size(), 100u);
  const std::vector<cv::Point2d> fitted = Project(estimate, bearings, {0, 0, 0}, {0, 0, 0});
  double worst = 0.0;
  for (size_t i = 0; i < bearings.size(); ++i) {
    worst = std::max(worst, std::hypot(fitted[i].x - back[i].x, fitted[i].y - back[i].y));
  }
  std::printf("projection of %zu bearings over the image: worst %.3f px from the true model\n",
              bearings.size(), worst);
  EXPECT_LT(worst, 0.5);
  EXPECT_NEAR(omni->intrinsics[2], 376.0, 2.0);
  EXPECT_NEAR(omni->intrinsics[3], 240.0, 2.0);

  // Kalibr's camchain: camera_model omni, intrinsics [xi, fu, fv, pu, pv], radtan.
  const std::string path = (support::FreshTempDir("omni") / "camchain.yaml").string();
  ASSERT_TRUE(io::WriteKalibrCamchain(path, {omni->ToCamchainEntry()}, "test").ok());
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_NE(text.str().find("camera_model: omni"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("distortion_model: radtan"), std::string::npos) << text.str();
  const size_t at = text.str().find("intrinsics: [");
  ASSERT_NE(at, std::string::npos) << text.str();
  const std::string list = text.str().substr(at, text.str().find(']', at) - at);
  EXPECT_EQ(std::count(list.begin(), list.end(), ','), 4) << list;  // five numbers, xi first
}

TEST(OmniIntrinsics, TooFewViewsIsAnError) {
  const pattern::CameraViews views = SimulatedViews(TrueOmni{}, 3, 6);
  auto omni = pattern::CalibrateOmni(views, 80);
  ASSERT_FALSE(omni.ok());
  EXPECT_NE(omni.error().find("needs at least 4"), std::string::npos) << omni.error();
}

}  // namespace
}  // namespace rigcal::pattern
