// SPDX-License-Identifier: Apache-2.0
// Affine patch alignment: recovers a known affine warp of a textured image, and on the rendered
// sewer and room sequences it removes the drift of frame-to-frame KLT tracks (tracked position
// against the projection of the true 3D point).
#include "../../vo/src/affine_patch.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <random>

#include "rigcal/base/robust_statistics.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::vo {
namespace {

cv::Mat RandomTexture(int width, int height, uint32_t seed) {
  cv::Mat noise(height / 4, width / 4, CV_32FC1);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::Mat big, out;
  cv::resize(noise, big, cv::Size(width, height), 0, 0, cv::INTER_CUBIC);
  cv::GaussianBlur(big, big, cv::Size(0, 0), 1.0);
  big.convertTo(out, CV_8UC1);
  return out;
}

TEST(AffinePatch, RecoversAKnownAffineWarp) {
  const cv::Mat image = RandomTexture(200, 200, 3);
  // The second image is the first warped: p2 = A p1 + t, plus an intensity offset of 6.
  Eigen::Matrix2d a;
  a << 1.15, 0.08, -0.05, 0.92;
  const Eigen::Vector2d t(4.3, -2.7);
  cv::Mat m = (cv::Mat_<double>(2, 3) << a(0, 0), a(0, 1), t.x(), a(1, 0), a(1, 1), t.y());
  cv::Mat warped;
  cv::warpAffine(image, warped, m, image.size(), cv::INTER_CUBIC);
  warped += cv::Scalar(6);
  AffinePatchOptions options;
  options.half_size = 7;
  options.max_iterations = 30;
  int aligned = 0;
  for (int y = 60; y <= 140; y += 20) {
    for (int x = 60; x <= 140; x += 20) {
      PatchTemplate patch;
      if (!MakePatchTemplate(image, cv::Point2f(x, y), options.half_size, &patch)) continue;
      const Eigen::Vector2d truth = a * Eigen::Vector2d(x, y) + t;
      Eigen::Matrix2d warp = Eigen::Matrix2d::Identity();
      Eigen::Vector2d centre = truth + Eigen::Vector2d(1.0, -0.8);  // 1.3 px off
      double rms = 0;
      ASSERT_TRUE(AlignPatch(patch, warped, options, &warp, &centre, &rms)) << x << " " << y;
      EXPECT_LT((centre - truth).norm(), 0.05) << x << " " << y;
      EXPECT_LT((warp - a).norm(), 0.02) << x << " " << y;
      ++aligned;
    }
  }
  EXPECT_GE(aligned, 20);
  // A flat patch is refused.
  PatchTemplate flat;
  EXPECT_FALSE(
      MakePatchTemplate(cv::Mat(50, 50, CV_8UC1, cv::Scalar(90)), cv::Point2f(25, 25), 5, &flat));
  // Out of the image: refused, never read outside.
  EXPECT_FALSE(MakePatchTemplate(image, cv::Point2f(2, 100), 5, &flat));
}

// KLT chains over `frames` frames of a config's camera, then the same tracks refined by
// aligning their first-frame patches: median distance to the projection of the true point.
void CompareWithKltChain(const std::string& file, int camera, int frames, double* klt_median,
                         double* affine_median) {
  auto config = io::LoadRigConfig(std::string(RIGCAL_SOURCE_DIR) + "/config/" + file);
  ASSERT_TRUE(config.ok()) << config.error();
  sim::SimulatedRigSpec spec = *config->simulated_source;
  spec.realtime = false;
  auto rig = sim::MakeSimulatedRig(spec);
  ASSERT_TRUE(rig.ok()) << rig.error();
  const camera::CameraModel& model = *spec.cameras[camera];
  auto pose = [&](int64_t k) { return rig->WorldFromCameraAt(camera, rig->FrameStreamTime(k)); };
  const int64_t first = 40;
  cv::Mat previous = rig->RenderFrame(camera, first);
  const cv::Mat reference = previous.clone();
  std::vector<cv::KeyPoint> corners;
  cv::FAST(previous, corners, 20, true);
  cv::KeyPointsFilter::retainBest(corners, 300);
  std::vector<cv::Point2f> points;
  std::vector<Eigen::Vector3d> world;
  const Pose p0 = pose(first);
  for (const cv::KeyPoint& c : corners) {
    if (c.pt.x < 20 || c.pt.y < 20 || c.pt.x > previous.cols - 20 || c.pt.y > previous.rows - 20) {
      continue;
    }
    const auto bearing = model.Unproject(Eigen::Vector2d(c.pt.x, c.pt.y));
    if (!bearing) continue;
    const Eigen::Vector3d d = p0.R() * bearing->normalized();
    const auto t = rig->CastRay(p0.C, d);
    if (!t) continue;
    points.push_back(c.pt);
    world.push_back(p0.C + *t * d);
  }
  const std::vector<cv::Point2f> reference_points = points;
  std::vector<char> alive(points.size(), 1);
  std::vector<Eigen::Matrix2d> warps(points.size(), Eigen::Matrix2d::Identity());
  std::vector<PatchTemplate> patches(points.size());
  AffinePatchOptions options;
  for (size_t i = 0; i < points.size(); ++i) {
    alive[i] = MakePatchTemplate(reference, reference_points[i], options.half_size, &patches[i]);
  }
  std::vector<Eigen::Vector2d> affine(points.size());
  for (size_t i = 0; i < points.size(); ++i) affine[i] = {points[i].x, points[i].y};
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  for (int f = 1; f <= frames; ++f) {
    const cv::Mat current = rig->RenderFrame(camera, first + f);
    std::vector<cv::Point2f> next = points;
    std::vector<unsigned char> ok;
    std::vector<float> error;
    cv::calcOpticalFlowPyrLK(previous, current, points, next, ok, error, cv::Size(15, 15), 2,
                             criteria);
    for (size_t i = 0; i < points.size(); ++i) {
      if (!alive[i] || !ok[i]) {
        alive[i] = 0;
        continue;
      }
      // Affine alignment from the reference patch, started at the KLT position with the
      // previous frame's warp.
      Eigen::Vector2d centre(next[i].x, next[i].y);
      if (!AlignPatch(patches[i], current, options, &warps[i], &centre) ||
          (centre - Eigen::Vector2d(next[i].x, next[i].y)).norm() > 2.0) {
        alive[i] = 0;
        continue;
      }
      affine[i] = centre;
    }
    points = next;
    previous = current;
  }
  std::vector<double> klt_errors, affine_errors;
  const Pose last = pose(first + frames);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!alive[i]) continue;
    const auto px = model.Project(last.R().transpose() * (world[i] - last.C));
    if (!px) continue;
    const double e_klt = (Eigen::Vector2d(points[i].x, points[i].y) - *px).norm();
    const double e_affine = (affine[i] - *px).norm();
    if (e_klt > 3.0) continue;  // occluded, or a depth edge
    klt_errors.push_back(e_klt);
    affine_errors.push_back(e_affine);
  }
  ASSERT_GE(klt_errors.size(), 50u) << file;
  *klt_median = UpperMedian(klt_errors);
  *affine_median = UpperMedian(affine_errors);
  std::printf(
      "%s camera %d, %d frames, %zu tracks: median error KLT chain %.3f px, affine %.3f px\n",
      file.c_str(), camera, frames, klt_errors.size(), *klt_median, *affine_median);
}

TEST(AffinePatch, RemovesTheDriftOfKltChainsInThePipe) {
  for (int camera : {0, 1}) {
    double klt = 0, affine = 0;
    CompareWithKltChain("sim_sewer.yaml", camera, 10, &klt, &affine);
    EXPECT_LT(affine, 0.5 * klt);
    EXPECT_LT(affine, 0.1);
  }
}

TEST(AffinePatch, RemovesTheDriftOfKltChainsInTheRoom) {
  double klt = 0, affine = 0;
  CompareWithKltChain("sim_thesis_virtual.yaml", 0, 10, &klt, &affine);
  EXPECT_LT(affine, klt);
  EXPECT_LT(affine, 0.06);
}

}  // namespace
}  // namespace rigcal::vo
