// SPDX-License-Identifier: Apache-2.0
// Moving objects of the simulated rig (source.scene.moving_objects): they appear in the frames
// where their boxes (SimulatedRig::MovingObjectsAt) say, in front of what they hide and behind
// what hides them; their texture moves with them by the pixels their motion projects to; a
// rolling shutter sees each row's position; the static scene and the ground truth stay as they
// are without them; their lines keep clear of the cameras.
// Reference: rays through the camera model cast against the boxes (slab test here) and the
// static scene (SimulatedRig::CastRay); the rendered object is where the same rig without
// moving objects renders something else (noise-free).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "rigcal/sim/simulated_rig.h"
#include "support/ideal_cameras.h"

namespace rigcal::sim {
namespace {

using support::PinholeWithFov;

SimulatedRigSpec::Waypoint Waypoint(const Eigen::Vector3d& p, double yaw, double pitch = 0,
                                    double roll = 0) {
  SimulatedRigSpec::Waypoint w;
  w.position = p;
  w.world_from_master = WaypointOrientationFromYpr(yaw, pitch, roll);
  return w;
}

// One 100-degree pinhole camera, 160 x 120, at rest 5.5 m above the floor of an 8 x 8 x 6 m
// room without boxes, looking straight down; three people-sized objects walking below it.
SimulatedRigSpec OverheadSpec() {
  SimulatedRigSpec spec;
  spec.names = {"cam0"};
  spec.cameras = {PinholeWithFov(160, 120, 100)};
  spec.master_from_camera = {Pose()};
  spec.waypoints = {Waypoint({0, 0, 5.5}, 0, 90), Waypoint({0, 0, 5.5}, 0, 90)};
  spec.waypoint_interval_s = 2.0;
  spec.frame_rate_hz = 20;
  spec.num_frames = 30;
  spec.noise_sigma = 0;
  spec.render_block = 1;  // exact casting: the reference is per pixel
  spec.seed = 3;
  spec.scene.size = Eigen::Vector3d(8, 8, 6);
  spec.scene.boxes = 0;
  spec.scene.moving_objects.count = 3;
  spec.scene.moving_objects.size_m = Eigen::Vector3d(0.6, 0.6, 1.8);
  spec.scene.moving_objects.speed_mps = 1.4;
  return spec;
}

// Two cameras looking out sideways while the rig moves through the default room with its boxes,
// and columns 8 m tall in the 6 m room: the ceiling hides their upper part (a static surface in
// front of a moving one), they hide the walls, boxes and each other.
SimulatedRigSpec ColumnsSpec() {
  SimulatedRigSpec spec;
  spec.names = {"cam0", "cam1"};
  spec.cameras = {PinholeWithFov(160, 120, 70), PinholeWithFov(160, 120, 70)};
  Pose right;
  right.q = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()));
  right.C = Eigen::Vector3d(-0.5, 0, 0);
  spec.master_from_camera = {Pose(), right};
  spec.waypoints = {Waypoint({-1, 0, 3}, 0, -20), Waypoint({0, 0.5, 3.2}, 40, -25),
                    Waypoint({1, 0, 2.8}, 90, -20)};
  spec.waypoint_interval_s = 2.0;
  spec.frame_rate_hz = 20;
  spec.noise_sigma = 0;
  spec.render_block = 1;
  spec.seed = 5;
  spec.scene.boxes = 10;
  spec.scene.moving_objects.count = 8;
  spec.scene.moving_objects.size_m = Eigen::Vector3d(1.0, 1.0, 8.0);
  spec.scene.moving_objects.speed_mps = 2.0;
  return spec;
}

SimulatedRig Make(const SimulatedRigSpec& spec) {
  auto rig = MakeSimulatedRig(spec);
  EXPECT_TRUE(rig) << rig.error();
  return std::move(rig).value();
}

SimulatedRig WithoutObjects(SimulatedRigSpec spec) {
  spec.scene.moving_objects.count = 0;
  return Make(spec);
}

// Distance along o + t d (d unit) at which the ray enters `box`, or nullopt.
std::optional<double> Entry(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& o,
                            const Eigen::Vector3d& d) {
  double t_near = -INFINITY, t_far = INFINITY;
  for (int a = 0; a < 3; ++a) {
    const double t1 = (box.min()[a] - o[a]) / d[a];
    const double t2 = (box.max()[a] - o[a]) / d[a];
    t_near = std::max(t_near, std::min(t1, t2));
    t_far = std::min(t_far, std::max(t1, t2));
  }
  if (t_near > t_far || t_near <= 0) return std::nullopt;
  return t_near;
}

// Per pixel of `camera` in frame k: the moving object it sees (its index), or -1 (the static
// scene, which is nearer where both are hit). Row r is seen at the frame's time plus
// `row_delay_s` x r / (height - 1). `hidden` (optional): counts the pixels whose ray passes
// through an object behind a static surface.
std::vector<int> ExpectedObjects(const SimulatedRig& rig, int camera, int64_t k, double row_delay_s,
                                 int* hidden = nullptr) {
  const camera::CameraModel& model = *rig.spec().cameras[camera];
  const int w = model.width(), h = model.height();
  std::vector<int> label(static_cast<size_t>(w) * h, -1);
  for (int y = 0; y < h; ++y) {
    const double t_s = rig.FrameStreamTime(k) + row_delay_s * y / (h - 1);
    const Pose world_from_camera = rig.WorldFromCameraAt(camera, t_s);
    const std::vector<Eigen::AlignedBox3d> boxes = rig.MovingObjectsAt(t_s);
    for (int x = 0; x < w; ++x) {
      const Eigen::Vector3d d = world_from_camera.R() * *model.Unproject(Eigen::Vector2d(x, y));
      const double t_static = rig.CastRay(world_from_camera.C, d).value_or(INFINITY);
      double best = INFINITY;
      for (size_t i = 0; i < boxes.size(); ++i) {
        const std::optional<double> t = Entry(boxes[i], world_from_camera.C, d);
        if (!t) continue;
        if (*t < t_static && *t < best) {
          best = *t;
          label[static_cast<size_t>(y) * w + x] = static_cast<int>(i);
        } else if (*t >= t_static && hidden != nullptr) {
          ++*hidden;
        }
      }
    }
  }
  return label;
}

struct MaskComparison {
  int expected = 0;  // pixels on an object by the reference
  int missed = 0;    // of those, rendered as the static scene
  int spurious = 0;  // pixels off every object whose value differs from the static render
};

MaskComparison Compare(const cv::Mat& with, const cv::Mat& without, const std::vector<int>& label) {
  MaskComparison c;
  for (int y = 0; y < with.rows; ++y) {
    for (int x = 0; x < with.cols; ++x) {
      const bool differs = with.at<uint8_t>(y, x) != without.at<uint8_t>(y, x);
      if (label[static_cast<size_t>(y) * with.cols + x] >= 0) {
        ++c.expected;
        c.missed += differs ? 0 : 1;  // the object's texture may match the background's by chance
      } else {
        c.spurious += differs ? 1 : 0;
      }
    }
  }
  return c;
}

TEST(MovingObjects, AppearWhereTheirBoxesSayAndNowhereElse) {
  const SimulatedRigSpec spec = OverheadSpec();
  const SimulatedRig rig = Make(spec);
  const SimulatedRig still = WithoutObjects(spec);
  ASSERT_EQ(rig.MovingObjectsAt(0).size(), 3u);
  int seen = 0;
  for (int64_t k : {0, 9, 18, 27}) {
    const std::vector<int> label = ExpectedObjects(rig, 0, k, 0.0);
    const MaskComparison c = Compare(rig.RenderFrame(0, k), still.RenderFrame(0, k), label);
    seen += c.expected;
    EXPECT_EQ(c.spurious, 0) << "frame " << k;
    EXPECT_LE(c.missed, c.expected / 20 + 2) << "frame " << k << ": " << c.expected;
  }
  EXPECT_GT(seen, 400);  // the objects are in view: ~11 x 11 px tops and their sides
}

TEST(MovingObjects, TextureMovesByTheProjectedMotion) {
  const SimulatedRigSpec spec = OverheadSpec();
  const SimulatedRig rig = Make(spec);
  const camera::CameraModel& model = *spec.cameras[0];
  const double top = spec.scene.moving_objects.size_m.z();
  int checked = 0;
  for (int64_t k = 2; k + 1 < rig.num_frames(); k += 6) {
    const cv::Mat a = rig.RenderFrame(0, k);
    const cv::Mat b = rig.RenderFrame(0, k + 1);
    const std::vector<int> label = ExpectedObjects(rig, 0, k, 0.0);
    const Pose world_from_camera = rig.WorldFromCameraAt(0, 0.0);
    for (int i = 0; i < 3; ++i) {
      // The top face is parallel to the image: its image translates by the projected motion.
      auto project = [&](double t_s) {
        Eigen::Vector3d c = rig.MovingObjectsAt(t_s)[static_cast<size_t>(i)].center();
        c.z() = top;
        return *model.Project(world_from_camera.Inverse().R() * (c - world_from_camera.C));
      };
      const Eigen::Vector2d shift =
          project(rig.FrameStreamTime(k + 1)) - project(rig.FrameStreamTime(k));
      // Mean absolute difference of the face's interior pixels in frame k to frame k + 1 at
      // `s` further (bilinear).
      auto mad = [&](const Eigen::Vector2d& s) {
        double sum = 0;
        int n = 0;
        for (int y = 2; y + 2 < a.rows; ++y) {
          for (int x = 2; x + 2 < a.cols; ++x) {
            bool interior = true;
            for (int dy = -2; dy <= 2; ++dy) {
              for (int dx = -2; dx <= 2; ++dx) {
                interior = interior && label[static_cast<size_t>(y + dy) * a.cols + x + dx] == i;
              }
            }
            const Eigen::Vector2d p = Eigen::Vector2d(x, y) + s;
            const int px = static_cast<int>(std::floor(p.x())),
                      py = static_cast<int>(std::floor(p.y()));
            if (!interior || px < 0 || py < 0 || px + 1 >= b.cols || py + 1 >= b.rows) continue;
            const double fx = p.x() - px, fy = p.y() - py;
            auto at = [&](int xx, int yy) { return static_cast<double>(b.at<uint8_t>(yy, xx)); };
            const double v = (1 - fy) * ((1 - fx) * at(px, py) + fx * at(px + 1, py)) +
                             fy * ((1 - fx) * at(px, py + 1) + fx * at(px + 1, py + 1));
            sum += std::abs(v - a.at<uint8_t>(y, x));
            ++n;
          }
        }
        return n >= 12 ? sum / n : NAN;
      };
      const double at_shift = mad(shift);
      if (std::isnan(at_shift)) continue;  // the object's top is not (well) in view
      ++checked;
      EXPECT_GT(shift.norm(), 0.8) << "object " << i << " frame " << k;  // 1.4 m/s at 3.7 m
      EXPECT_LT(at_shift, 0.5 * mad(Eigen::Vector2d::Zero())) << "object " << i << " frame " << k;
      EXPECT_LT(at_shift, 0.7 * mad(shift + 0.7 * shift.normalized()))
          << "object " << i << " frame " << k;
      EXPECT_LT(at_shift, 0.7 * mad(shift - 0.7 * shift.normalized()))
          << "object " << i << " frame " << k;
    }
  }
  EXPECT_GE(checked, 4);
}

// Objects cut by the image border are drawn as far as they are in view (the renderer skips only
// the objects whose bounding sphere lies outside every ray's cone): pixels on an object in a
// band along the border are not rendered as the static scene more often than elsewhere (where
// an object's texture equals the background's by chance, < 1 %).
TEST(MovingObjects, ObjectsAtTheBorderOfTheViewAreDrawn) {
  SimulatedRigSpec spec = OverheadSpec();
  spec.cameras = {PinholeWithFov(160, 120, 90)};
  spec.waypoints = {Waypoint({-3.6, 0, 1.2}, -35, 5), Waypoint({-3.6, 0.5, 1.2}, 35, -5)};
  spec.scene.moving_objects.count = 12;
  const SimulatedRig rig = Make(spec);
  const SimulatedRig still = WithoutObjects(spec);
  int on_object = 0, missed = 0, spurious = 0, border_on_object = 0, border_missed = 0;
  for (int64_t k = 0; k < rig.num_frames(); k += 3) {
    const std::vector<int> label = ExpectedObjects(rig, 0, k, 0.0);
    const cv::Mat with = rig.RenderFrame(0, k);
    const cv::Mat without = still.RenderFrame(0, k);
    for (int y = 0; y < with.rows; ++y) {
      for (int x = 0; x < with.cols; ++x) {
        const bool differs = with.at<uint8_t>(y, x) != without.at<uint8_t>(y, x);
        const bool border = x < 16 || x >= with.cols - 16 || y < 12 || y >= with.rows - 12;
        if (label[static_cast<size_t>(y) * with.cols + x] < 0) {
          spurious += differs ? 1 : 0;
          continue;
        }
        ++on_object;
        missed += differs ? 0 : 1;
        border_on_object += border ? 1 : 0;
        border_missed += border && !differs ? 1 : 0;
      }
    }
  }
  std::printf(
      "object pixels %d, rendered as the static scene %d (in the border band %d of %d), "
      "other pixels changed %d\n",
      on_object, missed, border_missed, border_on_object, spurious);
  EXPECT_GT(border_on_object, 2000);
  EXPECT_EQ(spurious, 0);
  EXPECT_LE(missed, on_object / 100);
  EXPECT_LE(border_missed, border_on_object / 100);
}

TEST(MovingObjects, RollingShutterSeesEachRowsPosition) {
  SimulatedRigSpec spec = OverheadSpec();
  spec.rolling_shutter_s = 0.04;
  spec.scene.moving_objects.speed_mps = 5.0;  // 20 cm during the readout: ~4 px
  const SimulatedRig rig = Make(spec);
  const SimulatedRig still = WithoutObjects(spec);
  int expected = 0, missed = 0, spurious = 0, global_errors = 0;
  for (int64_t k : {3, 11, 19}) {
    const cv::Mat with = rig.RenderFrame(0, k);
    const cv::Mat without = still.RenderFrame(0, k);
    const MaskComparison rows = Compare(with, without, ExpectedObjects(rig, 0, k, 0.04));
    const MaskComparison global = Compare(with, without, ExpectedObjects(rig, 0, k, 0.0));
    expected += rows.expected;
    missed += rows.missed;
    spurious += rows.spurious;
    global_errors += global.missed + global.spurious;
  }
  EXPECT_GT(expected, 300);
  EXPECT_EQ(spurious, 0);
  EXPECT_LE(missed, expected / 20);
  EXPECT_GT(global_errors, 10 * (missed + spurious) + 50);  // the frame's time alone is wrong
}

TEST(MovingObjects, OccludeAndAreOccludedByDepth) {
  const SimulatedRigSpec spec = ColumnsSpec();
  const SimulatedRig rig = Make(spec);
  const SimulatedRig still = WithoutObjects(spec);
  int expected = 0, missed = 0, spurious = 0, hidden = 0;
  for (int camera = 0; camera < 2; ++camera) {
    for (int64_t k = 0; k < rig.num_frames(); k += 20) {
      const MaskComparison c = Compare(rig.RenderFrame(camera, k), still.RenderFrame(camera, k),
                                       ExpectedObjects(rig, camera, k, 0.0, &hidden));
      expected += c.expected;
      missed += c.missed;
      spurious += c.spurious;
    }
  }
  EXPECT_GT(expected, 2000);
  EXPECT_GT(hidden, 1000);  // the ceiling in front of the columns' tops, columns behind columns
  EXPECT_EQ(spurious, 0);
  EXPECT_LE(missed, expected / 20);
}

TEST(MovingObjects, BlockRenderingDrawsTheSameObjects) {
  SimulatedRigSpec spec = ColumnsSpec();
  spec.render_block = 4;
  const SimulatedRig rig = Make(spec);
  const SimulatedRig still = WithoutObjects(spec);
  int expected = 0, missed = 0, spurious = 0;
  for (int64_t k = 0; k < rig.num_frames(); k += 30) {
    const MaskComparison c =
        Compare(rig.RenderFrame(0, k), still.RenderFrame(0, k), ExpectedObjects(rig, 0, k, 0.0));
    expected += c.expected;
    missed += c.missed;
    spurious += c.spurious;
  }
  // Blocks with an object's corner are cast per pixel: the silhouettes are exact but for
  // corners no node sees; their static neighbours differ from interpolated ones by a grey level.
  EXPECT_GT(expected, 1000);
  EXPECT_LE(missed, expected / 10);
  EXPECT_LE(spurious, expected / 5);
}

TEST(MovingObjects, StaticSceneAndGroundTruthAreUnchanged) {
  SimulatedRigSpec spec = ColumnsSpec();
  spec.render_block = 4;
  spec.noise_sigma = 2.0;
  const SimulatedRig rig = Make(spec);
  const SimulatedRig still = WithoutObjects(spec);
  const SimulatedGroundTruth a = rig.GroundTruth();
  const SimulatedGroundTruth b = still.GroundTruth();
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (size_t c = 0; c < a.cameras.size(); ++c) {
    EXPECT_EQ(a.cameras[c].t_ns, b.cameras[c].t_ns);
    ASSERT_EQ(a.cameras[c].world_from_camera.size(), b.cameras[c].world_from_camera.size());
    for (size_t k = 0; k < a.cameras[c].world_from_camera.size(); ++k) {
      EXPECT_EQ(a.cameras[c].world_from_camera[k].C, b.cameras[c].world_from_camera[k].C);
      EXPECT_EQ(a.cameras[c].world_from_camera[k].q.coeffs(),
                b.cameras[c].world_from_camera[k].q.coeffs());
    }
  }
  // A view has no time: RenderView is the static scene, the same with and without objects.
  const Pose pose = rig.WorldFromCameraAt(0, 1.0);
  EXPECT_EQ(cv::norm(rig.RenderView(0, pose), still.RenderView(0, pose), cv::NORM_INF), 0.0);
  EXPECT_TRUE(rig.MovingObjectsAt(1.0).size() == 8 && still.MovingObjectsAt(1.0).empty());
}

TEST(MovingObjects, LinesKeepClearOfTheCamerasAndAreReproducible) {
  const SimulatedRigSpec spec = ColumnsSpec();
  const SimulatedRig rig = Make(spec);
  const SimulatedRig again = Make(spec);
  for (int64_t q = 0; q < 4 * rig.num_frames(); ++q) {
    const double t_s = q * 0.25 / spec.frame_rate_hz;
    const std::vector<Eigen::AlignedBox3d> boxes = rig.MovingObjectsAt(t_s);
    const std::vector<Eigen::AlignedBox3d> same = again.MovingObjectsAt(t_s);
    for (size_t i = 0; i < boxes.size(); ++i) {
      EXPECT_EQ(boxes[i].min(), same[i].min());
      for (int camera = 0; camera < 2; ++camera) {
        const Eigen::Vector3d c = rig.WorldFromCameraAt(camera, t_s).C;
        EXPECT_GE(boxes[i].exteriorDistance(c), kMovingObjectClearance) << "t " << t_s;
      }
    }
  }
  // Speed: the centres move 2 m/s except where they turn back.
  const Eigen::Vector3d step =
      rig.MovingObjectsAt(1.01)[0].center() - rig.MovingObjectsAt(1.0)[0].center();
  EXPECT_NEAR(step.norm(), 0.02, 1e-9);
  // Too many, too big: an error that names the key.
  SimulatedRigSpec crowded = spec;
  crowded.scene.moving_objects.count = 64;
  crowded.scene.moving_objects.size_m = Eigen::Vector3d(6, 6, 8);
  auto bad = MakeSimulatedRig(crowded);
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().find("scene.moving_objects: object"), std::string::npos) << bad.error();
}

TEST(MovingObjects, SpecCheckNamesTheField) {
  struct Case {
    void (*change)(SimulatedRigSpec*);
    const char* field;
  };
  const Case cases[] = {
      {[](SimulatedRigSpec* s) { s->scene.moving_objects.count = 65; },
       "scene.moving_objects.count"},
      {[](SimulatedRigSpec* s) { s->scene.moving_objects.size_m.y() = 0; },
       "scene.moving_objects.size"},
      {[](SimulatedRigSpec* s) { s->scene.moving_objects.speed_mps = NAN; },
       "scene.moving_objects.speed_mps"},
      {[](SimulatedRigSpec* s) { s->scene.type = SimulatedRigSpec::SceneType::kPipe; },
       "scene.moving_objects: only in a room"},
  };
  for (const Case& c : cases) {
    SimulatedRigSpec spec = OverheadSpec();
    c.change(&spec);
    const Status status = spec.Check();
    ASSERT_FALSE(status.ok()) << c.field;
    EXPECT_NE(status.message().find(c.field), std::string::npos) << status.message();
  }
}

}  // namespace
}  // namespace rigcal::sim
