// SPDX-License-Identifier: Apache-2.0
// ChArUco boards: views rendered from a drawn board through a known pinhole camera (no
// distortion) at varied poses, some showing only part of the board, are detected and calibrate
// the camera back; bad input gets errors naming what is wrong.
#include "rigcal/pattern/charuco.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include "rigcal/pattern/intrinsics.h"
#include "support/temp_dir.h"

namespace rigcal::pattern {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

constexpr int kWidth = 640, kHeight = 480;
constexpr double kFx = 520.0, kFy = 515.0, kCx = 322.0, kCy = 236.0;
constexpr int kPixelsPerSquare = 40;

pattern::CharucoSpec Board() {
  pattern::CharucoSpec b;
  b.squares_x = 5;
  b.squares_y = 7;
  b.square_size = 0.04;
  b.marker_size = 0.03;
  b.dictionary = "DICT_4X4_50";
  return b;
}

// Renders the drawn board (one square margin, kPixelsPerSquare per square) as seen by the
// camera from board-frame pose (rotation vector `rv`, camera centre `c`, metres): the
// homography K [r1 r2 t] S, S mapping board-image pixels to board metres.
cv::Mat Render(const cv::Mat& board_image, const pattern::CharucoSpec& b, const Eigen::Vector3d& rv,
               const Eigen::Vector3d& c) {
  const Eigen::Matrix3d R_cb = Eigen::AngleAxisd(rv.norm(), rv.normalized()).toRotationMatrix();
  const Eigen::Vector3d t = -R_cb * c;  // board -> camera
  Eigen::Matrix3d K;
  K << kFx, 0, kCx, 0, kFy, kCy, 0, 0, 1;
  Eigen::Matrix3d P;
  P.col(0) = R_cb.col(0);
  P.col(1) = R_cb.col(1);
  P.col(2) = t;
  const double m = b.square_size / kPixelsPerSquare;  // metres per board-image pixel
  Eigen::Matrix3d S;
  // Board-image pixel centres (u + 0.5) minus the margin; OpenCV's board corner 0 is at the
  // image's bottom-left square corner in its y-up convention: flip y.
  const double height = (b.squares_y + 2) * kPixelsPerSquare;
  S << m, 0, (0.5 - kPixelsPerSquare) * m, 0, -m, (height - 0.5 - kPixelsPerSquare) * m, 0, 0, 1;
  const Eigen::Matrix3d H = K * P * S;
  cv::Mat h(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) h.at<double>(r, k) = H(r, k);
  cv::Mat out;
  cv::warpPerspective(board_image, out, h, cv::Size(kWidth, kHeight), cv::INTER_AREA,
                      cv::BORDER_CONSTANT, cv::Scalar(128));
  return out;
}

// The views' corners as a homography of their board positions (the rendering has no
// distortion): the largest distance of a corner from the view's least-squares fit, pixels (a
// corner misplaced by d keeps most of d: a view has 6 or more corners).
double LargestHomographyResidual(const pattern::TargetView& v) {
  std::vector<cv::Point2f> board, image;
  for (size_t i = 0; i < v.pixels.size(); ++i) {
    board.emplace_back(static_cast<float>(v.target_points[i].x()),
                       static_cast<float>(v.target_points[i].y()));
    image.emplace_back(static_cast<float>(v.pixels[i].x()), static_cast<float>(v.pixels[i].y()));
  }
  const cv::Mat H = cv::findHomography(board, image, 0);
  if (H.empty()) return std::numeric_limits<double>::infinity();
  std::vector<cv::Point2f> fitted;
  cv::perspectiveTransform(board, fitted, H);
  double largest = 0.0;
  for (size_t i = 0; i < image.size(); ++i) {
    largest = std::max(largest, static_cast<double>(cv::norm(fitted[i] - image[i])));
  }
  return largest;
}

// Several sets of 16 views, each drawn from its own seed: a corner misplaced by the detection
// shows in some sets only (it did in half of them while the markers' corners were refined).
TEST(Charuco, RenderedViewsCalibrateTheCamera) {
  const fs::path dir = support::FreshTempDir("charuco_views");
  const pattern::CharucoSpec board = Board();
  ASSERT_TRUE(pattern::DrawCharucoBoard(board, kPixelsPerSquare, (dir / "board.png").string()).ok());
  const cv::Mat board_image = cv::imread((dir / "board.png").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(board_image.empty());
  for (const uint64_t seed : {1, 2, 3, 4, 5, 6}) {
    SCOPED_TRACE("view set " + std::to_string(seed));
    const fs::path cam = dir / ("cam" + std::to_string(seed));
    fs::create_directories(cam);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> tilt(-0.5, 0.5), shift(-0.06, 0.06), dist(0.30, 0.45);
    const Eigen::Vector3d centre(0.10, 0.14, 0.0);  // the board's middle, metres
    for (int k = 0; k < 16; ++k) {
      // Looking at the board (its +z away from the camera) from a tilted direction; a few views
      // close up, showing part of the board only. Drawn one by one, last component first (the
      // order of RandomVector3, calib/synthetic.h): the order in which a constructor's
      // arguments are evaluated is unspecified, and the views would differ between compilers.
      const double rv_z = 0.3 * tilt(rng);
      const double rv_y = tilt(rng);
      const Eigen::Vector3d rv(M_PI + tilt(rng), rv_y, rv_z);
      const Eigen::Matrix3d R_cb = Eigen::AngleAxisd(rv.norm(), rv.normalized()).toRotationMatrix();
      const double d = k < 3 ? 0.18 : dist(rng);
      const double shift_y = shift(rng);
      const Eigen::Vector3d c =
          centre + Eigen::Vector3d(shift(rng), shift_y, 0) - d * R_cb.transpose().col(2);
      cv::Mat image = Render(board_image, board, rv, c);
      cv::imwrite((cam / ("view" + std::to_string(k) + ".png")).string(), image);
    }
    auto views = pattern::DetectCharucoViews("cam0", cam.string(), board);
    ASSERT_TRUE(views.ok()) << views.error();
    EXPECT_EQ(views->width, kWidth);
    EXPECT_GE(views->views.size(), 14u) << "views without a board: " << views->none.size();
    size_t partial = 0;
    for (const pattern::TargetView& v : views->views) {
      partial += v.pixels.size() < static_cast<size_t>(4 * 6) ? 1 : 0;
      for (const Eigen::Vector3d& p : v.target_points) {
        EXPECT_GE(p.x(), 0.0);
        EXPECT_LE(p.x(), 5 * 0.04 + 1e-6);
        EXPECT_EQ(p.z(), 0.0);
      }
      // Corner noise of a view rendered at 40-90 px per square is below 0.1 px: 0.5 px is far
      // beyond it and far below the 4-7 px of a corner settled towards a marker's corner.
      EXPECT_LT(LargestHomographyResidual(v), 0.5) << v.file;
    }
    EXPECT_GE(partial, 1u) << "no view showed part of the board only";
    pattern::IntrinsicsOptions options;
    options.reject_outliers = false;
    auto result = pattern::CalibrateIntrinsics(*views, options);
    ASSERT_TRUE(result.ok()) << result.error();
    // With ~16 views of ~24 corners at that noise the focal length is determined to well under
    // 0.1 % and the principal point to a fraction of a pixel. The bounds are issue 18's for real
    // data (0.5 %, 2 px).
    const auto& in = result->spec.intrinsics;
    std::printf(
        "ChArUco set %d: %d views, rms %.3f px, fx %.2f fy %.2f cx %.2f cy %.2f (truth %.0f %.0f "
        "%.0f %.0f)\n",
        static_cast<int>(seed), result->views_used, result->rms_px, in[0], in[1], in[2], in[3], kFx,
        kFy, kCx, kCy);
    EXPECT_LT(result->rms_px, 0.2);
    EXPECT_NEAR(in[0], kFx, 0.005 * kFx);
    EXPECT_NEAR(in[1], kFy, 0.005 * kFy);
    EXPECT_NEAR(in[2], kCx, 2.0);
    EXPECT_NEAR(in[3], kCy, 2.0);
  }
}

TEST(Charuco, BadInputIsNamed) {
  pattern::CharucoSpec b = Board();
  b.marker_size = 0.05;
  EXPECT_THAT(b.Check().message(), HasSubstr("marker_size"));
  b = Board();
  b.dictionary = "DICT_9X9";
  EXPECT_THAT(b.Check().message(), HasSubstr("unknown 'DICT_9X9'"));
  b = Board();
  b.squares_x = 20;
  b.squares_y = 20;  // 200 markers
  EXPECT_THAT(b.Check().message(), HasSubstr("DICT_4X4_50 has 50 markers"));
  pattern::CharucoSpec parsed;
  EXPECT_TRUE(pattern::ParseCharucoSquares("6x9", &parsed).ok());
  EXPECT_EQ(parsed.squares_x, 6);
  EXPECT_EQ(parsed.squares_y, 9);
  EXPECT_THAT(pattern::ParseCharucoSquares("6by9", &parsed).message(), HasSubstr("'6by9'"));

  // Images without a board: the error names the source and the board looked for.
  const fs::path dir = support::FreshTempDir("charuco_none");
  cv::imwrite((dir / "a.png").string(), cv::Mat(480, 640, CV_8U, cv::Scalar(90)));
  auto none = pattern::DetectCharucoViews("cam0", dir.string(), Board());
  ASSERT_FALSE(none.ok());
  EXPECT_THAT(none.error(), HasSubstr(dir.string()));
  EXPECT_THAT(none.error(), HasSubstr("5x7 ChArUco board"));
}

}  // namespace
}  // namespace rigcal::pattern
