// SPDX-License-Identifier: Apache-2.0
// The simulated rig: rendering geometry against the camera model, determinism, noise, blur,
// device behaviour (frame times, drops, jitter, failures, interrupt), spec checks. The cost per
// frame is a benchmark (tests/bench/render_bench.cc).
// The cameras are rigcal_camera's ideal pinhole and equidistant models (support/ideal_cameras.h),
// whose projections tests/camera/ checks against their equations: here they are the reference
// the renderer must agree with.
#include "rigcal/sim/simulated_rig.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <thread>
#include <tuple>

#include "support/ideal_cameras.h"

namespace rigcal::sim {
namespace {

using support::IdealEquidistant;
using support::IdealPinhole;
using support::PinholeWithFov;

Pose Mounting(const Eigen::Quaterniond& q, const Eigen::Vector3d& c) {
  Pose p;
  p.q = q;
  p.C = c;
  return p;
}

SimulatedRigSpec::Waypoint Waypoint(const Eigen::Vector3d& p, double yaw, double pitch = 0,
                                    double roll = 0) {
  SimulatedRigSpec::Waypoint w;
  w.position = p;
  w.world_from_master = WaypointOrientationFromYpr(yaw, pitch, roll);
  return w;
}

// Two cameras (a pinhole master and a slave looking right, 0.5 m to its left) moving and
// turning gently in the default room.
SimulatedRigSpec TwoCameraSpec(int width = 160, int height = 120) {
  SimulatedRigSpec spec;
  spec.names = {"cam0", "cam1"};
  spec.cameras = {PinholeWithFov(width, height, 60), PinholeWithFov(width, height, 60)};
  spec.master_from_camera = {
      Pose(), Mounting(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())),
                       Eigen::Vector3d(-0.5, 0, 0))};
  spec.waypoints = {Waypoint({-2, 0, 3}, 0), Waypoint({0, 1, 3.2}, 20, 10, -5),
                    Waypoint({2, 0, 2.8}, -15, -5, 10), Waypoint({0, -1, 3}, 30)};
  spec.waypoint_interval_s = 2.0;
  spec.frame_rate_hz = 20;
  spec.noise_sigma = 0;
  spec.seed = 7;
  return spec;
}

SimulatedRig Make(SimulatedRigSpec spec) {
  auto rig = MakeSimulatedRig(std::move(spec));
  EXPECT_TRUE(rig) << rig.error();
  return std::move(rig).value();
}

Pose LookingAlongX(const Eigen::Vector3d& position, double yaw = 0, double pitch = 0) {
  return Mounting(WaypointOrientationFromYpr(yaw, pitch, 0), position);
}

double SampleBilinear(const cv::Mat& image, const Eigen::Vector2d& p) {
  const int x = static_cast<int>(std::floor(p.x()));
  const int y = static_cast<int>(std::floor(p.y()));
  const double ax = p.x() - x, ay = p.y() - y;
  auto at = [&](int xx, int yy) { return static_cast<double>(image.at<uint8_t>(yy, xx)); };
  return (1 - ay) * ((1 - ax) * at(x, y) + ax * at(x + 1, y)) +
         ay * ((1 - ax) * at(x, y + 1) + ax * at(x + 1, y + 1));
}

TEST(SimulatedRigSpec, CheckNamesTheField) {
  ASSERT_TRUE(MakeSimulatedRig(TwoCameraSpec()));
  struct Case {
    std::function<void(SimulatedRigSpec*)> change;
    std::string field;
  };
  const std::vector<Case> cases = {
      {[](SimulatedRigSpec* s) { s->frame_rate_hz = 0; }, "frame_rate_hz"},
      {[](SimulatedRigSpec* s) { s->num_frames = 1000; }, "num_frames: 1000 frames at 20 Hz"},
      {[](SimulatedRigSpec* s) {
         s->num_frames = 10;
         s->duration_s = 1;
       },
       "num_frames, duration_s"},
      {[](SimulatedRigSpec* s) { s->waypoints.resize(1); }, "trajectory.waypoints"},
      {[](SimulatedRigSpec* s) { s->waypoints.clear(); }, "trajectory"},
      {[](SimulatedRigSpec* s) { s->noise_sigma = -1; }, "noise_sigma"},
      {[](SimulatedRigSpec* s) { s->blur_exposure_s = 0.06; }, "motion_blur.exposure_ms"},
      {[](SimulatedRigSpec* s) { s->rolling_shutter_s = -1e-3; }, "rolling_shutter_ms"},
      {[](SimulatedRigSpec* s) { s->rolling_shutter_s = 0.05; }, "rolling_shutter_ms"},
      {[](SimulatedRigSpec* s) { s->drop_probability = 1; }, "drop_probability"},
      {[](SimulatedRigSpec* s) { s->timestamp_jitter_s = 0.01; }, "timestamp_jitter_ms"},
      {[](SimulatedRigSpec* s) { s->fail_after_s["cam7"] = 1; }, "fail_after_s.cam7"},
      {[](SimulatedRigSpec* s) { s->render_block = 0; }, "render_block"},
      {[](SimulatedRigSpec* s) { s->scene.boxes = 100; }, "scene.boxes"},
      {[](SimulatedRigSpec* s) { s->names[1] = "cam0"; }, "duplicate camera name"},
      {[](SimulatedRigSpec* s) { s->cameras.pop_back(); }, "cameras"},
      {[](SimulatedRigSpec* s) { s->master_from_camera[0].C.x() = 1; }, "cam0.truth"},
      {[](SimulatedRigSpec* s) { s->master_from_camera[1].q.coeffs() *= 2; }, "cam1.truth"},
  };
  for (const Case& c : cases) {
    SimulatedRigSpec spec = TwoCameraSpec();
    c.change(&spec);
    const Status status = spec.Check();
    EXPECT_FALSE(status.ok()) << c.field;
    EXPECT_NE(status.message().find(c.field), std::string::npos)
        << "'" << c.field << "' not in: " << status.message();
    EXPECT_FALSE(MakeSimulatedRig(spec)) << c.field;
  }
}

TEST(SimulatedRig, CameraLeavingTheFreeSpaceIsAnError) {
  SimulatedRigSpec spec = TwoCameraSpec();
  spec.waypoints.back().position = Eigen::Vector3d(0, 0, 5.99);  // ceiling at 6 m
  auto rig = MakeSimulatedRig(spec);
  ASSERT_FALSE(rig);
  EXPECT_NE(rig.error().find("trajectory: camera cam"), std::string::npos) << rig.error();
  EXPECT_NE(rig.error().find("leaves the room"), std::string::npos) << rig.error();
}

TEST(SimulatedRig, TrajectoryStartsAndEndsAtTheWaypointsAndIsSmooth) {
  const SimulatedRigSpec spec = TwoCameraSpec();
  const SimulatedRig rig = Make(spec);
  EXPECT_EQ(rig.num_frames(), 121);  // 6 s at 20 Hz, both ends included
  const Pose start = rig.WorldFromMasterAt(0.0);
  const Pose end = rig.WorldFromMasterAt(6.0);
  EXPECT_LT((start.C - spec.waypoints.front().position).norm(), 1e-12);
  EXPECT_LT((end.C - spec.waypoints.back().position).norm(), 1e-12);
  EXPECT_LT(start.q.angularDistance(spec.waypoints.front().world_from_master), 1e-9);
  EXPECT_LT(end.q.angularDistance(spec.waypoints.back().world_from_master), 1e-9);
  // Velocity and angular velocity are continuous (C2 spline): no jump at the knots.
  const double h = 1e-4;
  for (double knot : {2.0, 4.0}) {
    const Eigen::Vector3d v_before =
        (rig.WorldFromMasterAt(knot).C - rig.WorldFromMasterAt(knot - h).C) / h;
    const Eigen::Vector3d v_after =
        (rig.WorldFromMasterAt(knot + h).C - rig.WorldFromMasterAt(knot).C) / h;
    EXPECT_LT((v_before - v_after).norm(), 1e-3) << knot;
    const double w_before =
        rig.WorldFromMasterAt(knot).q.angularDistance(rig.WorldFromMasterAt(knot - h).q) / h;
    const double w_after =
        rig.WorldFromMasterAt(knot + h).q.angularDistance(rig.WorldFromMasterAt(knot).q) / h;
    EXPECT_NEAR(w_before, w_after, 1e-3) << knot;
  }
  // The slave follows its mounting.
  const Pose slave = rig.WorldFromCameraAt(1, 3.3);
  const Pose expected = rig.WorldFromMasterAt(3.3) * spec.master_from_camera[1];
  EXPECT_LT((slave.C - expected.C).norm(), 1e-12);
}

TEST(SimulatedRig, RayDistanceToRoomWallIsAnalytic) {
  const SimulatedRig rig = Make(TwoCameraSpec());  // room [-10, 10] x [-8, 8] x [0, 6]
  const Eigen::Vector3d o(1.5, -0.5, 3.0);
  ASSERT_TRUE(rig.CastRay(o, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(*rig.CastRay(o, Eigen::Vector3d::UnitZ()), 3.0, 1e-12);   // ceiling
  EXPECT_NEAR(*rig.CastRay(o, -Eigen::Vector3d::UnitZ()), 3.0, 1e-12);  // floor
  // Obliquely up to the ceiling: 3 m up along a 60-degree ray is 6 m.
  const Eigen::Vector3d d(std::cos(M_PI / 6), 0, 0.5);
  EXPECT_NEAR(*rig.CastRay(o, d), 6.0, 1e-9);
  // The centre pixel of the master looking along +y at the +y wall (y = 8), when no box is in
  // between: distance 8.5 m.
  const Pose view = LookingAlongX(o, 90);
  const Eigen::Vector3d centre_ray = view.R() * Eigen::Vector3d::UnitZ();
  const auto t = rig.CastRay(o, centre_ray);
  ASSERT_TRUE(t);
  EXPECT_LE(*t, 8.5 + 1e-9);  // a box along the wall may be nearer
  SimulatedRigSpec no_boxes = TwoCameraSpec();
  no_boxes.scene.boxes = 0;
  EXPECT_NEAR(*Make(no_boxes).CastRay(o, centre_ray), 8.5, 1e-9);
}

TEST(SimulatedRig, PipeRayDistances) {
  SimulatedRigSpec spec = TwoCameraSpec();
  spec.scene.type = SimulatedRigSpec::SceneType::kPipe;
  spec.master_from_camera[1].C = Eigen::Vector3d(0, 0, -0.2);
  spec.waypoints = {Waypoint({1, 0.05, 0}, 0), Waypoint({2, 0.05, 0}, 0)};
  const SimulatedRig rig = Make(spec);
  const Eigen::Vector3d o(1.5, 0.1, 0.0);
  EXPECT_NEAR(*rig.CastRay(o, Eigen::Vector3d::UnitY()), 0.2, 1e-12);
  EXPECT_NEAR(*rig.CastRay(o, -Eigen::Vector3d::UnitY()), 0.4, 1e-12);
  EXPECT_NEAR(*rig.CastRay(o, Eigen::Vector3d::UnitZ()), std::sqrt(0.09 - 0.01), 1e-12);
  EXPECT_NEAR(*rig.CastRay(o, Eigen::Vector3d::UnitX()), 40.0 - 1.5, 1e-12);  // end cap
}

// The top edge of a yard wall against the smooth sky: every column of a noise-free image turns
// from sky to wall exactly at the first pixel row below the edge's projection.
void ExpectWallTopAtProjection(int block) {
  SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  spec.scene.type = SimulatedRigSpec::SceneType::kYard;  // walls at x = +-30, 8 m high
  spec.scene.boxes = 0;
  spec.waypoints = {Waypoint({10, 0, 6}, 0), Waypoint({11, 0, 6}, 0)};
  const SimulatedRig rig = Make(spec);
  const auto& camera = spec.cameras[0];
  const Pose view = LookingAlongX({14, 0.3, 6.0}, 4.0, 1.0);  // slight yaw and pitch
  const cv::Mat image = rig.RenderView(0, view, block);
  int checked = 0, exact = 0;
  for (int x = 0; x < image.cols; ++x) {
    // The wall's top edge (30, y, 8) as seen by this column: intersect the column's plane.
    const Eigen::Vector3d top_row = view.R() * *camera->Unproject({double(x), 0.0}, nullptr);
    const Eigen::Vector3d bottom_row =
        view.R() * *camera->Unproject({double(x), image.rows - 1.0}, nullptr);
    const Eigen::Vector3d normal = top_row.cross(bottom_row);  // column plane through the centre
    // Point on the edge line p(s) = (30, s, 8) in that plane: normal . (p(s) - C) = 0.
    const Eigen::Vector3d c = view.C;
    const double s = -(normal.x() * (30 - c.x()) + normal.z() * (8 - c.z())) / normal.y() + c.y();
    const Eigen::Vector3d edge_cam = view.R().transpose() * (Eigen::Vector3d(30, s, 8) - c);
    const auto px = camera->Project(edge_cam, nullptr);
    ASSERT_TRUE(px);
    ASSERT_NEAR(px->x(), x, 1e-6);
    const int first_wall_row = static_cast<int>(std::ceil(px->y()));
    if (first_wall_row < 2 || first_wall_row >= image.rows - 2) continue;
    // The sky's intensity is a smooth function of direction; the wall is textured.
    int found = -1;
    for (int y = 0; y < image.rows && found < 0; ++y) {
      const Eigen::Vector3d d = view.R() * *camera->Unproject({double(x), double(y)}, nullptr);
      const double sky = 160.0 + 60.0 * d.normalized().z();
      if (std::abs(image.at<uint8_t>(y, x) - sky) > 1.01) found = y;
    }
    ++checked;
    exact += found == first_wall_row;
  }
  ASSERT_GT(checked, 300);
  // A wall texel may match the sky's grey by chance, which delays the detected edge.
  EXPECT_GE(exact, 0.97 * checked) << "block " << block << ": " << exact << " of " << checked;
}

TEST(SimulatedRig, WallEdgeAppearsWhereTheModelProjectsIt) {
  ExpectWallTopAtProjection(1);
  ExpectWallTopAtProjection(4);
}

// Renders two views of the room; a pixel of view A and the projection into view B of the 3D
// point that A's pixel sees must show the same texture.
double RegistrationError(const SimulatedRig& rig, int cam_a, const Pose& a, int cam_b,
                         const Pose& b, const camera::CameraModel& model_a,
                         const camera::CameraModel& model_b, const Eigen::Vector2d& shift,
                         int* count) {
  const cv::Mat image_a = rig.RenderView(cam_a, a, 1);
  const cv::Mat image_b = rig.RenderView(cam_b, b, 1);
  double sum = 0;
  *count = 0;
  for (int y = 8; y < image_a.rows - 8; y += 3) {
    for (int x = 8; x < image_a.cols - 8; x += 3) {
      const auto bearing = model_a.Unproject({double(x), double(y)}, nullptr);
      if (!bearing) continue;
      const Eigen::Vector3d d = a.R() * *bearing;
      const auto t = rig.CastRay(a.C, d);
      if (!t) continue;
      const Eigen::Vector3d point = a.C + *t * d;
      // Skip points near a depth edge of view A or hidden in view B.
      const Eigen::Vector3d to_point = point - b.C;
      const auto t_b = rig.CastRay(b.C, to_point);
      if (!t_b || std::abs(*t_b - 1.0) > 1e-6) continue;
      const auto px = model_b.Project(b.R().transpose() * to_point, nullptr);
      if (!px) continue;
      const Eigen::Vector2d q = *px + shift;
      if (q.x() < 1 || q.y() < 1 || q.x() > image_b.cols - 3 || q.y() > image_b.rows - 3) {
        continue;
      }
      sum += std::abs(image_a.at<uint8_t>(y, x) - SampleBilinear(image_b, q));
      ++*count;
    }
  }
  return *count > 0 ? sum / *count : 1e9;
}

TEST(SimulatedRig, TwoViewsAgreeThroughProjection) {
  const SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  const SimulatedRig rig = Make(spec);
  const Pose a = LookingAlongX({0, 0, 3}, 10, 5);
  const Pose b = LookingAlongX({0.3, 0.4, 3.1}, 14, 2);
  int n = 0, n_shifted = 0;
  const double error = RegistrationError(rig, 0, a, 0, b, *spec.cameras[0], *spec.cameras[0],
                                         Eigen::Vector2d::Zero(), &n);
  const double shifted = RegistrationError(rig, 0, a, 0, b, *spec.cameras[0], *spec.cameras[0],
                                           Eigen::Vector2d(1.5, 0), &n_shifted);
  std::printf("pinhole two-view registration: %.2f grey levels (%d points); 1.5 px off: %.2f\n",
              error, n, shifted);
  EXPECT_GT(n, 3000);
  EXPECT_LT(error, 4.0);
  EXPECT_LT(error, 0.5 * shifted);
}

TEST(SimulatedRig, FisheyeBeyond180DegreesAgreesWithPinhole) {
  // A 200-degree fisheye master and a pinhole looking 95 degrees to its side and slightly
  // back, from the same centre: the pinhole's pixels are seen by the fisheye at bearings with
  // z < 0.
  SimulatedRigSpec spec = TwoCameraSpec();
  const double f = 100.0;  // px / rad: 0.01 rad per pixel on both cameras
  spec.cameras = {IdealEquidistant(360, 360, f, 100.0), IdealPinhole(160, 120, f, f, 79.5, 59.5)};
  const SimulatedRig rig = Make(spec);
  const Pose a = LookingAlongX({0, 0, 3}, 0);
  const Pose b = LookingAlongX({0, 0, 3}, 95);
  int n = 0, n_shifted = 0;
  const double error = RegistrationError(rig, 1, b, 0, a, *spec.cameras[1], *spec.cameras[0],
                                         Eigen::Vector2d::Zero(), &n);
  const double shifted = RegistrationError(rig, 1, b, 0, a, *spec.cameras[1], *spec.cameras[0],
                                           Eigen::Vector2d(0, 2.0), &n_shifted);
  std::printf(
      "fisheye (z < 0) vs pinhole registration: %.2f grey levels (%d points); 2 px off: "
      "%.2f\n",
      error, n, shifted);
  EXPECT_GT(n, 500);
  EXPECT_LT(error, 6.0);
  EXPECT_LT(error, 0.6 * shifted);
  // Outside the 200-degree image circle the image is black.
  const cv::Mat image = rig.RenderView(0, a);
  EXPECT_EQ(image.at<uint8_t>(0, 0), 0);
  EXPECT_GT(cv::mean(image(cv::Rect(150, 150, 60, 60)))[0], 20.0);
}

TEST(SimulatedRig, BlockInterpolationMatchesExactRendering) {
  SimulatedRigSpec spec = TwoCameraSpec(752, 480);
  const SimulatedRig rig = Make(spec);
  for (const Pose& view : {LookingAlongX({-2, 0, 3}, 10, 5), LookingAlongX({1, 2, 1.0}, -60, 30),
                           LookingAlongX({0, 0, 5.5}, 30, -40)}) {
    const cv::Mat exact = rig.RenderView(0, view, 1);
    const cv::Mat fast = rig.RenderView(0, view, 4);
    cv::Mat diff;
    cv::absdiff(exact, fast, diff);
    const double mean = cv::mean(diff)[0];
    double max_diff = 0;
    cv::minMaxLoc(diff, nullptr, &max_diff);
    const double above2 = cv::countNonZero(diff > 2) / static_cast<double>(diff.total());
    std::printf("block 4 vs exact: mean |diff| %.3f, max %.0f grey levels, %.2f%% of pixels > 2\n",
                mean, max_diff, 100 * above2);
    EXPECT_LT(mean, 0.25);
    EXPECT_LT(above2, 0.01);
  }
}

TEST(SimulatedRig, DeterministicForASeed) {
  SimulatedRigSpec spec = TwoCameraSpec();
  spec.noise_sigma = 3;
  spec.blur_exposure_s = 0.01;
  spec.blur_samples = 3;
  const SimulatedRig a = Make(spec);
  const SimulatedRig b = Make(spec);
  for (int64_t k : {0, 17, 60}) {
    for (int c = 0; c < 2; ++c) {
      EXPECT_EQ(cv::norm(a.RenderFrame(c, k), b.RenderFrame(c, k), cv::NORM_INF), 0.0);
    }
  }
  // Devices render the same frames as RenderFrame, whichever thread runs them.
  auto device = a.MakeDevice(1);
  std::vector<cv::Mat> grabbed;
  std::thread thread([&] {
    for (int i = 0; i < 3; ++i) grabbed.push_back((*device->Grab())->image);
  });
  thread.join();
  for (int k = 0; k < 3; ++k)
    EXPECT_EQ(cv::norm(grabbed[k], b.RenderFrame(1, k), cv::NORM_INF), 0.0);
  // Another seed: other textures and noise.
  spec.seed = 8;
  const SimulatedRig c = Make(spec);
  EXPECT_GT(cv::norm(a.RenderFrame(0, 0), c.RenderFrame(0, 0), cv::NORM_L1) / (160 * 120), 10.0);
}

TEST(SimulatedRig, NoiseHasTheConfiguredSigma) {
  SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  spec.noise_sigma = 4;
  const SimulatedRig rig = Make(spec);
  const cv::Mat noisy = rig.RenderFrame(0, 10);
  const cv::Mat clean = rig.RenderView(0, rig.WorldFromCameraAt(0, rig.FrameStreamTime(10)));
  double sum = 0, sum2 = 0;
  int n = 0;
  for (int y = 0; y < noisy.rows; ++y) {
    for (int x = 0; x < noisy.cols; ++x) {
      const int c = clean.at<uint8_t>(y, x);
      if (c < 20 || c > 235) continue;  // away from saturation
      const double d = noisy.at<uint8_t>(y, x) - c;
      sum += d;
      sum2 += d * d;
      ++n;
    }
  }
  const double mean = sum / n;
  const double sigma = std::sqrt(sum2 / n - mean * mean);
  // Quantisation of both images adds about 1/12 + 1/12 grey levels^2 of variance.
  const double expected = std::sqrt(16.0 + 2.0 / 12.0);
  std::printf("noise: mean %.3f, sigma %.3f (expected %.3f), %d pixels\n", mean, sigma, expected,
              n);
  EXPECT_NEAR(mean, 0.0, 0.1);
  EXPECT_NEAR(sigma, expected, 0.1);
}

double GradientEnergy(const cv::Mat& image) {
  cv::Mat gx;
  cv::Sobel(image, gx, CV_32F, 1, 0);
  return cv::mean(cv::abs(gx))[0];
}

TEST(SimulatedRig, MotionBlurSmoothsMovingImages) {
  SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  // A fast pan: 40 degrees in 0.5 s.
  spec.waypoints = {Waypoint({0, 0, 3}, 0), Waypoint({0, 0, 3}, 40)};
  spec.waypoint_interval_s = 0.5;
  const SimulatedRig sharp = Make(spec);
  spec.blur_exposure_s = 0.02;
  spec.blur_samples = 8;
  const SimulatedRig blurred = Make(spec);
  const double e_sharp = GradientEnergy(sharp.RenderFrame(0, 5));
  const double e_blur = GradientEnergy(blurred.RenderFrame(0, 5));
  std::printf("horizontal gradient energy: sharp %.2f, blurred %.2f\n", e_sharp, e_blur);
  EXPECT_LT(e_blur, 0.7 * e_sharp);
  // A camera at rest is not blurred.
  spec.waypoints = {Waypoint({0, 0, 3}, 0), Waypoint({0, 0, 3}, 0)};
  spec.blur_exposure_s = 0;
  const SimulatedRig still = Make(spec);
  spec.blur_exposure_s = 0.02;
  const SimulatedRig still_blurred = Make(spec);
  EXPECT_LE(cv::norm(still.RenderFrame(0, 3), still_blurred.RenderFrame(0, 3), cv::NORM_INF), 1.0);
}

// source.blur_burst_s: the camera's frames in the span are blurred over 90 % of the frame
// period, every other frame (and every other camera) is rendered as without it, bit for bit.
TEST(SimulatedRig, BlurBurstBlursOnlyItsSpan) {
  SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  spec.waypoints = {Waypoint({0, 0, 3}, 0), Waypoint({0, 0, 3}, 40)};  // 40 degrees in 0.5 s
  spec.waypoint_interval_s = 0.5;
  const SimulatedRig sharp = Make(spec);
  const double period_s = 1.0 / spec.frame_rate_hz;
  spec.blur_burst_s["cam0"] = {4.5 * period_s, 6.5 * period_s};  // frames 5 and 6
  const SimulatedRig burst = Make(spec);
  for (int64_t k : {3, 4, 7}) {
    EXPECT_EQ(cv::norm(sharp.RenderFrame(0, k), burst.RenderFrame(0, k), cv::NORM_INF), 0.0) << k;
  }
  for (int64_t k : {5, 6}) {
    EXPECT_EQ(cv::norm(sharp.RenderFrame(1, k), burst.RenderFrame(1, k), cv::NORM_INF), 0.0) << k;
    const double e_sharp = GradientEnergy(sharp.RenderFrame(0, k));
    const double e_burst = GradientEnergy(burst.RenderFrame(0, k));
    EXPECT_LT(e_burst, 0.7 * e_sharp) << k;
  }
  spec.blur_burst_s["cam7"] = {0.0, 1.0};
  EXPECT_NE(spec.Check().message().find("blur_burst_s.cam7"), std::string::npos);
}

// source.vignetting: the light falls to 1 - v of the centre's at the corners, quadratically in
// the radius; the centre is as without it.
TEST(SimulatedRig, VignettingDarkensTheCornersByItsStrength) {
  SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  const SimulatedRig plain = Make(spec);
  spec.vignetting = 0.4;
  const SimulatedRig vignetted = Make(spec);
  const cv::Mat a = plain.RenderFrame(0, 3), b = vignetted.RenderFrame(0, 3);
  cv::Mat fa, fb;
  a.convertTo(fa, CV_64F);
  b.convertTo(fb, CV_64F);
  // Sums over 20 x 20 patches: at the centre, at a corner and halfway out along the diagonal
  // (radius² 1/4 of the corner's). Rounding: half a grey level per pixel at most.
  const auto ratio = [&](int x, int y) {
    const cv::Rect patch(x - 10, y - 10, 20, 20);
    return cv::sum(fb(patch))[0] / cv::sum(fa(patch))[0];
  };
  const double cx = 159.5, cy = 119.5, r2_corner = cx * cx + cy * cy;
  const auto expected = [&](int x, int y) {
    const double dx = x - 0.5 - cx, dy = y - 0.5 - cy;  // the patch's centre
    return 1.0 - 0.4 * (dx * dx + dy * dy) / r2_corner;
  };
  for (const auto& [x, y] : std::vector<std::pair<int, int>>{{160, 120}, {240, 180}, {10, 10}}) {
    const double mean = cv::sum(fa(cv::Rect(x - 10, y - 10, 20, 20)))[0] / 400.0;
    EXPECT_NEAR(ratio(x, y), expected(x, y), 0.02 + 0.5 / mean) << x << ", " << y;
  }
  spec.vignetting = 1.0;
  EXPECT_NE(spec.Check().message().find("vignetting"), std::string::npos);
}

// source.scene.textures: the surfaces take their tiles from the photographs in turn. Constant
// photographs make the proof exact: every level of a constant tile's mip pyramid, every
// bilinear sample of it and so every rendered pixel (no noise, no light effects) is that
// constant, while the procedural dead leaves show dozens of grey levels.
SimulatedRigSpec::GreyImage ConstantPhoto(uint8_t grey, int width = 40, int height = 24) {
  SimulatedRigSpec::GreyImage photo;
  photo.name = "grey " + std::to_string(grey);
  photo.width = width;
  photo.height = height;
  photo.pixels.assign(static_cast<size_t>(width) * height, grey);
  return photo;
}

int DistinctGreyLevels(const cv::Mat& image) {
  std::vector<bool> seen(256, false);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) seen[image.at<uint8_t>(y, x)] = true;
  }
  return static_cast<int>(std::count(seen.begin(), seen.end(), true));
}

TEST(SimulatedRig, PhotoTexturesReplaceTheProceduralOnes) {
  EXPECT_GT(DistinctGreyLevels(Make(TwoCameraSpec()).RenderFrame(0, 3)), 50);

  SimulatedRigSpec one = TwoCameraSpec();
  one.scene.textures = {ConstantPhoto(90)};
  const cv::Mat flat = Make(one).RenderFrame(0, 3);
  EXPECT_EQ(cv::countNonZero(flat != 90), 0) << "every surface shows the one photograph";

  SimulatedRigSpec two = TwoCameraSpec();
  two.scene.textures = {ConstantPhoto(60), ConstantPhoto(180, 17, 33)};
  const SimulatedRig rig = Make(two);
  int dark = 0, bright = 0, total = 0;
  for (int k = 0; k < 40; k += 13) {
    const cv::Mat image = rig.RenderFrame(0, k);
    dark += cv::countNonZero(image == 60);
    bright += cv::countNonZero(image == 180);
    total += static_cast<int>(image.total());
  }
  EXPECT_EQ(dark + bright, total) << "each surface shows one of the two photographs";
  EXPECT_GT(dark, 0);
  EXPECT_GT(bright, 0);

  SimulatedRigSpec tiny = TwoCameraSpec();
  tiny.scene.textures = {ConstantPhoto(90, 8, 8)};
  const auto refused = MakeSimulatedRig(tiny);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().find("scene.textures[0]"), std::string::npos) << refused.error();
}

// A camera turning about its vertical axis at a constant rate: a sampled trajectory between two
// orientations 40 degrees apart over 1 s (slerp, so ω is constant), at a fixed position.
SimulatedRigSpec PanningSpec(double rolling_shutter_s) {
  SimulatedRigSpec spec = TwoCameraSpec(320, 240);
  spec.waypoints.clear();
  spec.trajectory_t_ns = {0, 1'000'000'000};
  spec.trajectory_world_from_body = {LookingAlongX({0, 0, 3}, 0), LookingAlongX({0, 0, 3}, 40)};
  spec.rolling_shutter_s = rolling_shutter_s;
  return spec;
}

// The horizontal shift s (px) that best maps rows [y0, y1) and columns [x0, x1) of `image` onto
// `reference` sampled at (x + s, y + dy(x, y)): least mean absolute difference, searched over
// [-10, 10] px in steps of 0.05 px, then 0.005 px around the best.
double BestHorizontalShift(const cv::Mat& image, const cv::Mat& reference, int x0, int x1, int y0,
                           int y1, const std::function<double(int, int)>& dy) {
  const auto cost = [&](double s) {
    double sum = 0;
    for (int y = y0; y < y1; ++y) {
      for (int x = x0; x < x1; ++x) {
        const Eigen::Vector2d q(x + s, y + dy(x, y));
        sum += std::abs(image.at<uint8_t>(y, x) - SampleBilinear(reference, q));
      }
    }
    return sum;
  };
  double best = 0, best_cost = 1e300;
  for (const auto& [from, to, step] :
       std::vector<std::tuple<double, double, double>>{{-10, 10, 0.05}, {-0.05, 0.05, 0.005}}) {
    const double centre = best;
    for (double s = centre + from; s <= centre + to + 1e-9; s += step) {
      const double c = cost(s);
      if (c < best_cost) best_cost = c, best = s;
    }
  }
  return best;
}

// source.rolling_shutter_ms: row y is exposed r y / (H - 1) after the stamp (r the readout), so
// while the camera turns at ω about its vertical axis, row y shows the scene turned by
// θ(y) = ω r y / (H - 1) against the global-shutter image at the stamp: shifted horizontally by
// f tan θ ≈ f ω r y / (H - 1) px near the centre column, a shift linear in the row; the top row
// (the stamp's) is the global-shutter image's. Expected per band of rows: the exact projection
// of each pixel's bearing at its row's pose into the camera at the stamp (pure rotation: no
// depth), averaged over the band. The measured shift differs from it by the search step
// (0.005 px) plus the bias of resampling 8-bit images bilinearly (measured < 0.05 px): 0.1 px
// allowed, against a shift of f ω r = 277 x 0.70 x 0.03 = 5.8 px over the image.
TEST(SimulatedRig, RollingShutterShiftsEachRowByTheTurnDuringItsReadout) {
  const double readout_s = 0.03;
  const SimulatedRig global = Make(PanningSpec(0.0));
  const SimulatedRig rolling = Make(PanningSpec(readout_s));
  const int64_t k = 10;  // t = 0.5 s
  const cv::Mat g = global.RenderFrame(0, k), r = rolling.RenderFrame(0, k);
  const double t = rolling.FrameStreamTime(k);
  const camera::CameraModel& model = *rolling.spec().cameras[0];
  const Pose at_stamp = rolling.WorldFromCameraAt(0, t);
  // Where pixel (x, y) of the rolling-shutter image lies in the global-shutter image.
  const auto expected_px = [&](int x, int y) {
    const Pose at_row = rolling.WorldFromCameraAt(0, t + readout_s * y / (r.rows - 1));
    const Eigen::Vector3d world = at_row.R() * *model.Unproject({double(x), double(y)}, nullptr);
    return *model.Project(at_stamp.R().transpose() * world, nullptr);
  };
  EXPECT_EQ(cv::norm(g.row(0), r.row(0), cv::NORM_INF), 0.0) << "the stamp is the top row's";
  EXPECT_GT(cv::norm(g.rowRange(200, 240), r.rowRange(200, 240), cv::NORM_L1) / (40 * 320), 2.0);
  const double f = 160.0 / std::tan(30.0 * M_PI / 180.0);
  const double omega = 40.0 * M_PI / 180.0;
  const int x0 = 136, x1 = 184;  // the central 48 columns
  std::vector<double> rows, shifts;
  for (int y0 = 8; y0 + 16 <= r.rows - 8; y0 += 16) {
    double expected = 0;
    for (int y = y0; y < y0 + 16; ++y) {
      for (int x = x0; x < x1; ++x) expected += expected_px(x, y).x() - x;
    }
    expected /= 16.0 * (x1 - x0);
    const double measured = BestHorizontalShift(
        r, g, x0, x1, y0, y0 + 16, [&](int x, int y) { return expected_px(x, y).y() - y; });
    EXPECT_NEAR(measured, expected, 0.1) << "rows " << y0 << "..";
    rows.push_back(y0 + 7.5);
    shifts.push_back(measured);
  }
  // The shift grows linearly with the row at f ω r / (H - 1) px per row (near the centre
  // column; tan θ ≈ θ to 1e-4 here): least-squares slope within 2 % (0.1 px over the image).
  const double n = static_cast<double>(rows.size());
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (size_t i = 0; i < rows.size(); ++i) {
    sx += rows[i], sy += shifts[i], sxx += rows[i] * rows[i], sxy += rows[i] * shifts[i];
  }
  const double slope = (n * sxy - sx * sy) / (n * sxx - sx * sx);
  const double expected_slope = f * omega * readout_s / (r.rows - 1);
  std::printf("rolling shutter: %.4f px per row, expected %.4f\n", slope, expected_slope);
  EXPECT_NEAR(std::abs(slope), expected_slope, 0.02 * expected_slope);
}

// A camera at rest, or a readout of 0, renders the global-shutter image bit for bit.
TEST(SimulatedRig, RollingShutterOffOrAtRestIsTheGlobalShutterImage) {
  const SimulatedRig global = Make(PanningSpec(0.0));
  EXPECT_EQ(
      cv::norm(global.RenderFrame(0, 7), Make(PanningSpec(0.0)).RenderFrame(0, 7), cv::NORM_INF),
      0.0);
  SimulatedRigSpec still = PanningSpec(0.0);
  still.trajectory_world_from_body[1] = still.trajectory_world_from_body[0];
  const SimulatedRig still_global = Make(still);
  still.rolling_shutter_s = 0.03;
  still.blur_exposure_s = 0.0;
  EXPECT_EQ(cv::norm(still_global.RenderFrame(0, 7), Make(still).RenderFrame(0, 7), cv::NORM_INF),
            0.0);
}

// source.exposure_steps: the gain is 1 in the first interval and a factor within
// [1/max_factor, max_factor] in each later one, the same for all frames of an interval; the
// noise scales with it.
TEST(SimulatedRig, ExposureStepsScaleWholeIntervals) {
  SimulatedRigSpec spec = TwoCameraSpec(160, 120);
  spec.waypoints = {Waypoint({0, 0, 3}, 0), Waypoint({0, 0, 3}, 0)};  // at rest
  spec.waypoint_interval_s = 10.0;
  const SimulatedRig plain = Make(spec);
  spec.exposure_steps.interval_s = 0.5;  // 10 frames at 20 Hz
  spec.exposure_steps.max_factor = 1.5;
  const SimulatedRig stepped = Make(spec);
  const auto mean = [](const cv::Mat& m) { return cv::mean(m)[0]; };
  EXPECT_EQ(cv::norm(plain.RenderFrame(0, 4), stepped.RenderFrame(0, 4), cv::NORM_INF), 0.0);
  int changed = 0;
  for (int64_t step = 1; step <= 6; ++step) {
    const double gain =
        mean(stepped.RenderFrame(0, 10 * step)) / mean(plain.RenderFrame(0, 10 * step));
    const double again =
        mean(stepped.RenderFrame(0, 10 * step + 9)) / mean(plain.RenderFrame(0, 10 * step + 9));
    EXPECT_GE(gain, 1.0 / 1.5 - 0.01) << step;
    EXPECT_LE(gain, 1.5 + 0.01) << step;  // (saturation only lowers it)
    EXPECT_NEAR(again, gain, 0.01) << "one gain per interval, step " << step;
    changed += std::abs(gain - 1.0) > 0.02;
  }
  EXPECT_GE(changed, 4) << "the steps hardly change the gain";
  spec.exposure_steps.max_factor = 9.0;
  EXPECT_NE(spec.Check().message().find("exposure_steps.max_factor"), std::string::npos);
}

TEST(SimulatedCamera, FrameTimesDropsAndJitterMatchTheSpec) {
  SimulatedRigSpec spec = TwoCameraSpec(16, 12);
  spec.waypoint_interval_s = 40.0;  // 120 s: 2401 frames at 20 Hz
  spec.drop_probability = 0.2;
  spec.timestamp_jitter_s = 0.002;
  spec.start_time_ns = 1'000'000'000'000;
  const SimulatedRig rig = Make(spec);
  const int64_t frames = rig.num_frames();
  ASSERT_EQ(frames, 2401);
  for (int c = 0; c < 2; ++c) {
    auto device = rig.MakeDevice(c);
    EXPECT_EQ(device->name(), spec.names[c]);
    EXPECT_EQ(device->frame_rate_hz(), 20.0);
    int64_t received = 0, last_seq = -1, last_t = 0;
    double sum = 0, sum2 = 0, max_abs = 0;
    for (;;) {
      auto frame = device->Grab();
      ASSERT_TRUE(frame) << frame.error();
      if (!frame->has_value()) break;
      const capture::Frame& f = **frame;
      EXPECT_EQ(f.camera, c);
      EXPECT_GT(f.seq, last_seq);
      EXPECT_GT(f.t_ns, last_t);
      EXPECT_EQ(f.image.type(), CV_8UC1);
      last_seq = f.seq;
      last_t = f.t_ns;
      const double jitter = static_cast<double>(f.t_ns - rig.FrameTimeNs(f.seq)) * 1e-9;
      sum += jitter;
      sum2 += jitter * jitter;
      max_abs = std::max(max_abs, std::abs(jitter));
      ++received;
    }
    EXPECT_FALSE(*device->Grab());  // stays at the end
    EXPECT_EQ(received + device->dropped(), frames);
    const double p = static_cast<double>(device->dropped()) / frames;
    const double p_tolerance = 4.0 * std::sqrt(0.2 * 0.8 / frames);
    const double mean = sum / received;
    const double sigma = std::sqrt(sum2 / received - mean * mean);
    // Clipping a normal at 3 sigma leaves 98.6% of its standard deviation.
    const double expected_sigma = 0.002 * 0.9865;
    const double sigma_tolerance = 4.0 * expected_sigma / std::sqrt(2.0 * received);
    std::printf(
        "%s: %ld frames, drop rate %.4f (0.2 +- %.4f), jitter mean %.2f us, sigma %.4f "
        "ms (%.4f +- %.4f), max %.3f ms\n",
        spec.names[c].c_str(), static_cast<long>(received), p, p_tolerance, mean * 1e6, sigma * 1e3,
        expected_sigma * 1e3, sigma_tolerance * 1e3, max_abs * 1e3);
    EXPECT_NEAR(p, 0.2, p_tolerance);
    EXPECT_NEAR(mean, 0.0, 4.0 * 0.002 / std::sqrt(received));
    EXPECT_NEAR(sigma, expected_sigma, sigma_tolerance);
    EXPECT_LE(max_abs, 3 * 0.002 + 1e-9);
  }
  // Drops are independent per camera.
  EXPECT_EQ(rig.FrameTimeNs(0), spec.start_time_ns);
  EXPECT_EQ(rig.FrameTimeNs(3), spec.start_time_ns + 150'000'000);
}

TEST(SimulatedCamera, FailingCameraReturnsAnErrorAfterItsTime) {
  SimulatedRigSpec spec = TwoCameraSpec(16, 12);
  spec.fail_after_s["cam1"] = 0.5;
  const SimulatedRig rig = Make(spec);
  auto master = rig.MakeDevice(0);
  auto slave = rig.MakeDevice(1);
  int slave_frames = 0;
  for (;;) {
    auto frame = slave->Grab();
    if (!frame) {
      EXPECT_NE(frame.error().find("cam1"), std::string::npos) << frame.error();
      EXPECT_NE(frame.error().find("0.5"), std::string::npos) << frame.error();
      break;
    }
    ASSERT_TRUE(frame->has_value()) << "stream ended without the failure";
    EXPECT_LT(rig.FrameStreamTime((*frame)->seq), 0.5);
    ++slave_frames;
  }
  EXPECT_EQ(slave_frames, 10);  // frames at 0, 0.05, ..., 0.45 s
  EXPECT_FALSE(slave->Grab());  // stays failed
  int master_frames = 0;
  for (;;) {
    auto frame = master->Grab();
    ASSERT_TRUE(frame) << frame.error();
    if (!frame->has_value()) break;
    ++master_frames;
  }
  EXPECT_EQ(master_frames, rig.num_frames());
}

TEST(SimulatedCamera, RealtimeStampsAndInterrupt) {
  SimulatedRigSpec spec = TwoCameraSpec(16, 12);
  spec.realtime = true;
  spec.frame_rate_hz = 100;
  spec.num_frames = 5;
  const SimulatedRig rig = Make(spec);
  EXPECT_EQ(rig.epoch_ns(), 0);  // not started yet
  auto device = rig.MakeDevice(0);
  std::vector<int64_t> stamps;
  for (;;) {
    auto frame = device->Grab();
    ASSERT_TRUE(frame) << frame.error();
    if (!frame->has_value()) break;
    stamps.push_back((*frame)->t_ns);
  }
  ASSERT_GT(rig.epoch_ns(), 0);
  ASSERT_EQ(stamps.size() + device->late_skipped(), 5u);
  for (int64_t t : stamps) {
    EXPECT_EQ((t - rig.epoch_ns()) % 10'000'000, 0);  // on the 100 Hz grid, no jitter
  }
  // Interrupt before Grab: end of stream at once.
  auto other = rig.MakeDevice(1);
  other->Interrupt();
  auto frame = other->Grab();
  ASSERT_TRUE(frame);
  EXPECT_FALSE(frame->has_value());
  // Interrupt while Grab waits for a frame due in 10 s.
  spec.frame_rate_hz = 0.1;
  spec.num_frames = 0;
  spec.waypoint_interval_s = 20;
  const SimulatedRig slow = Make(spec);
  auto waiting = slow.MakeDevice(0);
  ASSERT_TRUE(*waiting->Grab());  // frame 0 is due at once
  std::optional<Expected<std::optional<capture::Frame>>> result;
  std::thread grabber([&] { result.emplace(waiting->Grab()); });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  waiting->Interrupt();
  grabber.join();
  ASSERT_TRUE(result && *result);
  EXPECT_FALSE((*result)->has_value());
}

}  // namespace
}  // namespace rigcal::sim
