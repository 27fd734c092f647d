// SPDX-License-Identifier: Apache-2.0
// Chessboard corners on rendered views (no distortion, a known pinhole camera) from near, where
// a square is ~42 px wide in the image, to far, ~12 px: every detected corner lies within a
// fraction of a pixel of its true image position at every distance.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#pragma GCC diagnostic pop

#include "rigcal/pattern/target_views.h"
#include "support/temp_dir.h"

namespace rigcal::pattern {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 640, kHeight = 480;
constexpr double kFx = 520.0, kFy = 515.0, kCx = 322.0, kCy = 236.0;
constexpr int kPixelsPerSquare = 40;  // of the drawn board

// The drawn board: (cols + 1) x (rows + 1) squares, a white margin of one square.
cv::Mat DrawBoard(const pattern::ChessboardSpec& spec) {
  const int squares_x = spec.cols + 1, squares_y = spec.rows + 1;
  cv::Mat board((squares_y + 2) * kPixelsPerSquare, (squares_x + 2) * kPixelsPerSquare, CV_8UC1,
                cv::Scalar(255));
  for (int r = 0; r < squares_y; ++r) {
    for (int c = 0; c < squares_x; ++c) {
      if ((r + c) % 2 != 0) continue;
      cv::rectangle(board,
                    cv::Rect((c + 1) * kPixelsPerSquare, (r + 1) * kPixelsPerSquare,
                             kPixelsPerSquare, kPixelsPerSquare),
                    cv::Scalar(0), cv::FILLED);
    }
  }
  return board;
}

struct RenderedView {
  cv::Mat image;
  std::vector<Eigen::Vector2d> corners;  // true image positions of the inner corners
};

// The board seen from `distance` metres along a tilted direction: the homography K [r1 r2 t] S,
// S mapping drawn-board pixel centres to board metres.
RenderedView Render(const cv::Mat& board, const pattern::ChessboardSpec& spec, double distance,
                    std::mt19937_64& rng) {
  std::uniform_real_distribution<double> tilt(-0.5, 0.5);
  const double about_z = 0.3 * tilt(rng), about_y = tilt(rng), about_x = tilt(rng);
  const Eigen::Vector3d rv(M_PI + about_x, about_y, about_z);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(rv.norm(), rv.normalized()).toRotationMatrix();
  const Eigen::Vector3d middle((spec.cols + 1) * spec.square_size / 2,
                               (spec.rows + 1) * spec.square_size / 2, 0.0);
  const Eigen::Vector3d t = -R * (middle - distance * R.transpose().col(2));
  Eigen::Matrix3d K, P, S;
  K << kFx, 0, kCx, 0, kFy, kCy, 0, 0, 1;
  P << R.col(0), R.col(1), t;
  const double m = spec.square_size / kPixelsPerSquare;
  S << m, 0, (0.5 - kPixelsPerSquare) * m, 0, m, (0.5 - kPixelsPerSquare) * m, 0, 0, 1;
  const Eigen::Matrix3d H = K * P * S;
  cv::Mat h(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) h.at<double>(r, c) = H(r, c);
  }
  RenderedView view;
  cv::warpPerspective(board, view.image, h, cv::Size(kWidth, kHeight), cv::INTER_LINEAR,
                      cv::BORDER_CONSTANT, cv::Scalar(128));
  for (int r = 1; r <= spec.rows; ++r) {
    for (int c = 1; c <= spec.cols; ++c) {
      const Eigen::Vector3d x =
          K * P * Eigen::Vector3d(c * spec.square_size, r * spec.square_size, 1);
      view.corners.emplace_back(x.x() / x.z(), x.y() / x.z());
    }
  }
  return view;
}

TEST(ChessboardRender, CornersStayOnTheirTruePositionsNearAndFar) {
  pattern::ChessboardSpec spec;  // 9 x 6 inner corners
  spec.square_size = 0.04;
  const cv::Mat board = DrawBoard(spec);
  std::mt19937_64 rng(3);
  for (const double distance : {0.5, 0.8, 1.1, 1.4, 1.7}) {
    const double square_px = kFx * spec.square_size / distance;
    SCOPED_TRACE("distance " + std::to_string(distance) + " m");
    const fs::path dir =
        support::FreshTempDir("chessboard_" + std::to_string(static_cast<int>(distance * 10)));
    std::vector<RenderedView> rendered;
    for (int k = 0; k < 8; ++k) {
      rendered.push_back(Render(board, spec, distance, rng));
      cv::imwrite((dir / ("view" + std::to_string(k) + ".png")).string(), rendered.back().image);
    }
    auto views = pattern::DetectChessboardViews("cam", dir.string(), spec);
    ASSERT_TRUE(views.ok()) << views.error();
    EXPECT_EQ(views->views.size(), rendered.size());
    // Each detected corner against the nearest true corner (the detector may number the grid
    // from either end).
    double sum2 = 0.0, largest = 0.0;
    int corners = 0;
    for (const pattern::TargetView& v : views->views) {
      const int k = std::stoi(fs::path(v.file).stem().string().substr(4));
      for (const Eigen::Vector2d& p : v.pixels) {
        double nearest = std::numeric_limits<double>::infinity();
        for (const Eigen::Vector2d& q : rendered[static_cast<size_t>(k)].corners) {
          nearest = std::min(nearest, (p - q).norm());
        }
        sum2 += nearest * nearest;
        largest = std::max(largest, nearest);
        ++corners;
      }
    }
    const double rms = std::sqrt(sum2 / std::max(corners, 1));
    std::printf(
        "chessboard at %.1f m (squares ~%.0f px): %d corners, error RMS %.3f px, max %.3f px\n",
        distance, square_px, corners, rms, largest);
    // Bilinear rendering of squares 12-42 px wide localises a corner to ~0.2 px; a refinement
    // window reaching the neighbouring corners moves them by a good part of a square (1.9 px
    // RMS at 15 px squares, 7.6 px at 12 px with a fixed 11 px half-window).
    EXPECT_LT(rms, 0.35);
    EXPECT_LT(largest, 1.0);
  }
}

}  // namespace
}  // namespace rigcal::pattern
