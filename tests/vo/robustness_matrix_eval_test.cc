// SPDX-License-Identifier: Apache-2.0
// The VO's robustness matrix (label eval): the thesis 5.4 virtual scene
// (config/sim_thesis_virtual.yaml, two 60-degree pinhole cameras, 468 frames at 20 Hz) rendered
// with one imaging effect at a time, at two strengths: motion blur over a fraction of the frame
// period, vignetting, auto-exposure steps with gain noise, image noise, barrel lens distortion
// (rendered through and undone by the camera model), coarser texture, dropped frames, real
// photographs of ../shared/data/real_mono as the textures (skipped without them), a rolling
// shutter of 15 and 30 ms readout (compensated by the VO: the cameras' models carry the
// readout); and moving objects at three strengths (8 and 48 people, 20 cars crossing the room,
// whose features the VO must reject; the fraction of each view they cover and how many of the
// VO's pose inliers per frame lie on them, or within 8 px of them, are printed under their
// rows). Per cell and camera: when the VO gives its first pose (stream seconds), the
// fraction of frames with a pose, scale segments, relocalisations and the RMS frame-to-frame
// rotation error; then the calibration of the two VO trajectories (RigEstimator over the
// synchronised sets, the history refinement at the end as `rigcal run` publishes it): state,
// rotation error and its σ, and the direction error of C (scale-free).
// Checked: without an effect both cameras track >= 90 % of the frames in one segment and the
// calibration is usable; in every cell, a usable calibration's rotation error is within 3 of its
// σ (an effect may cost accuracy, but the σ must say so) or the calibration is not usable.
// Run: ctest --test-dir build -L eval -R vo/robustness_matrix -V (~6 min). With
// RIGCAL_MATRIX_EFFECT=<text> set, only the effects whose name contains it run (and "none");
// RIGCAL_MATRIX_SEED=<n> renders another scene (textures, layout, noise, objects) than seed 1.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/refinement_job.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/sim/simulated_rig.h"
#include "rigcal/vo/monocular_vo.h"
#include "support/skip.h"

namespace rigcal::vo {
namespace {

struct Cell {
  std::string effect;
  std::string strength;
  std::function<void(sim::SimulatedRigSpec*)> apply;
  double drop_probability = 0.0;  // each camera's frames not fed to its VO
};

// A real photograph of ../shared/data/real_mono as a grey texture (empty pixels when missing:
// the rig's spec check then names it).
sim::SimulatedRigSpec::GreyImage RealPhoto(const std::string& relative) {
  const std::string file = std::string(RIGCAL_SHARED_DATA_DIR) + "/real_mono/" + relative;
  const cv::Mat grey = cv::imread(file, cv::IMREAD_GRAYSCALE);
  sim::SimulatedRigSpec::GreyImage photo;
  photo.name = file;
  if (grey.empty() || !grey.isContinuous()) return photo;
  photo.width = grey.cols;
  photo.height = grey.rows;
  photo.pixels.assign(grey.datastart, grey.dataend);
  return photo;
}

const std::vector<std::string> kPhotoFiles = {"visp_rbt_sequence/images/color_image_0000.png",
                                              "visp_rbt_sequence/images/color_image_0050.png",
                                              "visp_mbt_cube/images/image0000.png",
                                              "visp_mbt_cube/images/image0150.png"};

std::vector<Cell> Cells() {
  auto blur = [](double fraction) {
    return [fraction](sim::SimulatedRigSpec* s) {
      s->blur_exposure_s = fraction / s->frame_rate_hz;
      s->blur_samples = 6;
    };
  };
  auto vignetting = [](double v) { return [v](sim::SimulatedRigSpec* s) { s->vignetting = v; }; };
  auto exposure = [](double f) {
    return [f](sim::SimulatedRigSpec* s) {
      s->exposure_steps.interval_s = 2.0;
      s->exposure_steps.max_factor = f;
    };
  };
  auto noise = [](double sigma) {
    return [sigma](sim::SimulatedRigSpec* s) { s->noise_sigma = sigma; };
  };
  auto none = [](sim::SimulatedRigSpec*) {};
  // Coarser texture (the room's default is 1 cm per texel): fewer, softer corners at the same
  // distance, as on plain walls.
  auto texel = [](double m) { return [m](sim::SimulatedRigSpec* s) { s->scene.texel_m = m; }; };
  // Barrel distortion in both cameras' lens model (radial-tangential k1, k2), which the renderer
  // images through and the VO undoes with the same model.
  auto distortion = [](double k1) {
    return [k1](sim::SimulatedRigSpec* s) {
      for (auto& camera : s->cameras) {
        camera::CameraSpec lens;
        lens.model = camera::CameraSpec::Model::kPinhole;
        lens.width = camera->width();
        lens.height = camera->height();
        lens.intrinsics = {651.2511, 651.2511, 375.5, 239.5};  // the config's
        lens.distortion = {k1, 0.2 * k1 * k1, 0.0, 0.0};
        auto model = camera::MakeCameraModel(lens);
        EXPECT_TRUE(model.ok()) << model.error();
        if (model.ok()) camera = std::shared_ptr<const camera::CameraModel>(std::move(*model));
      }
    };
  };
  // Real photographs as the walls' and boxes' textures (real texture statistics: smooth shading,
  // large plain areas, repeated structure), at the room's 1 cm per texel and at 2 cm.
  auto photos = [](double texel_m) {
    return [texel_m](sim::SimulatedRigSpec* s) {
      for (const std::string& file : kPhotoFiles) s->scene.textures.push_back(RealPhoto(file));
      s->scene.texel_m = texel_m;
    };
  };
  // Rolling shutter: rows read out over `readout_ms` top to bottom (the stamp is the top
  // row's); both cameras' models carry the readout, so the VO moves each observation to the
  // stamp (vo/src/rolling_shutter.h).
  auto rolling = [](double readout_ms) {
    return [readout_ms](sim::SimulatedRigSpec* s) {
      s->rolling_shutter_s = readout_ms * 1e-3;
      for (auto& camera : s->cameras) {
        std::unique_ptr<camera::CameraModel> model = camera->Clone();
        model->set_rolling_shutter_s(s->rolling_shutter_s);
        camera = std::shared_ptr<const camera::CameraModel>(std::move(model));
      }
    };
  };
  // Moving objects crossing the room on their own lines: people (0.6 x 0.6 x 1.8 m, 1.4 m/s) or
  // cars (4 x 1.8 x 1.5 m, 6 m/s).
  auto moving = [](int count, const Eigen::Vector3d& size_m, double speed_mps) {
    return [=](sim::SimulatedRigSpec* s) {
      s->scene.moving_objects.count = count;
      s->scene.moving_objects.size_m = size_m;
      s->scene.moving_objects.speed_mps = speed_mps;
    };
  };
  const Eigen::Vector3d person(0.6, 0.6, 1.8);
  const Eigen::Vector3d car(4.0, 1.8, 1.5);
  return {{"none", "-", none},
          {"motion blur", "40% of period", blur(0.4)},
          {"motion blur", "80% of period", blur(0.8)},
          {"vignetting", "0.3", vignetting(0.3)},
          {"vignetting", "0.6", vignetting(0.6)},
          {"exposure steps", "x1.25 / 2 s", exposure(1.25)},
          {"exposure steps", "x1.6 / 2 s", exposure(1.6)},
          {"image noise", "6 grey", noise(6.0)},
          {"image noise", "12 grey", noise(12.0)},
          {"lens distortion", "k1 -0.15", distortion(-0.15)},
          {"lens distortion", "k1 -0.3", distortion(-0.3)},
          {"low texture", "texel 4 cm", texel(0.04)},
          {"low texture", "texel 8 cm", texel(0.08)},
          {"dropped frames", "10%", none, 0.1},
          {"dropped frames", "30%", none, 0.3},
          {"real-photo textures", "1 cm / texel", photos(0.01)},
          {"real-photo textures", "2 cm / texel", photos(0.02)},
          {"rolling shutter", "15 ms", rolling(15.0)},
          {"rolling shutter", "30 ms", rolling(30.0)},
          {"moving objects", "8 people", moving(8, person, 1.4)},
          {"moving objects", "48 people", moving(48, person, 1.4)},
          {"moving objects", "20 cars", moving(20, car, 6.0)}};
}

struct CameraFigures {
  double first_pose_s = NAN;
  int tracked = 0;
  int frames = 0;
  int segments = 0;
  int relocalisations = 0;
  double rotation_rms_deg = NAN;  // frame to frame, within a segment
  // With moving objects, per tracked frame: the VO's pose inliers whose pixel shows an object,
  // and those beside one (a pixel within kNearObjectPx shows one, the centre not).
  double inliers_on_objects = 0.0;
  double inliers_near_objects = 0.0;
};

// A feature within this distance of an object's outline has object pixels in its KLT window
// (VoOptions::klt_window_px 15) or affine patch (half size 5).
constexpr double kNearObjectPx = 8.0;

struct CellResult {
  std::vector<CameraFigures> cameras;
  // Per camera: mean and largest fraction of the pixels on moving objects (MovingCover).
  std::vector<double> moving_cover;
  std::vector<double> moving_cover_max;
  SlaveCalibration slave;
  double rotation_error_deg = NAN;
  double direction_error_deg = NAN;
};

double AngleDeg(const Eigen::Quaterniond& q) {
  return Eigen::AngleAxisd(q.normalized()).angle() * kDegPerRad;
}

// Distance along origin + s * direction (s > 0) at which the ray enters `box`, if it does.
std::optional<double> RayEntersBox(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
                                   const Eigen::AlignedBox3d& box) {
  double enter = 0.0, leave = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (direction[a] == 0.0) {
      if (origin[a] < box.min()[a] || origin[a] > box.max()[a]) return std::nullopt;
      continue;
    }
    double s0 = (box.min()[a] - origin[a]) / direction[a];
    double s1 = (box.max()[a] - origin[a]) / direction[a];
    if (s0 > s1) std::swap(s0, s1);
    enter = std::max(enter, s0);
    leave = std::min(leave, s1);
    if (enter > leave) return std::nullopt;
  }
  return enter;
}

// Whether pixel `px` of `camera` at frame k shows one of the moving objects `boxes` (their
// boxes then): its ray meets a box before the static scene.
bool ShowsMovingObject(const sim::SimulatedRig& rig, int camera, int64_t k,
                       const Eigen::Vector2d& px, const std::vector<Eigen::AlignedBox3d>& boxes) {
  const auto bearing = rig.spec().cameras[camera]->Unproject(px);
  if (!bearing) return false;
  const Pose world_from_camera = rig.WorldFromCameraAt(camera, rig.FrameStreamTime(k));
  const Eigen::Vector3d direction = world_from_camera.R() * *bearing;
  const std::optional<double> scene = rig.CastRay(world_from_camera.C, direction);
  for (const Eigen::AlignedBox3d& box : boxes) {
    const std::optional<double> s = RayEntersBox(world_from_camera.C, direction, box);
    if (s && (!scene || *s < *scene)) return true;
  }
  return false;
}

// Counts the pose inliers of frame k on moving objects and beside them (CameraFigures).
void CountObjectInliers(const sim::SimulatedRig& rig, int camera, int64_t k,
                        const std::vector<Eigen::Vector2f>& inlier_px, CameraFigures* figures) {
  const std::vector<Eigen::AlignedBox3d> boxes = rig.MovingObjectsAt(rig.FrameStreamTime(k));
  const double r = kNearObjectPx, h = 0.5 * kNearObjectPx;
  const Eigen::Vector2d around[] = {{r, 0}, {-r, 0}, {0, r}, {0, -r},
                                    {h, 0}, {-h, 0}, {0, h}, {0, -h}};
  for (const Eigen::Vector2f& p : inlier_px) {
    const Eigen::Vector2d px = p.cast<double>();
    if (ShowsMovingObject(rig, camera, k, px, boxes)) {
      figures->inliers_on_objects += 1.0;
      continue;
    }
    for (const Eigen::Vector2d& d : around) {
      if (ShowsMovingObject(rig, camera, k, px + d, boxes)) {
        figures->inliers_near_objects += 1.0;
        break;
      }
    }
  }
}

// One camera's VO over the frames the rig delivers (dropped frames are not fed); its poses by
// frame index (nullopt without one).
std::vector<std::optional<CameraPose>> RunVo(const sim::SimulatedRig& rig, int camera,
                                             double drop_probability, CameraFigures* figures) {
  std::mt19937 rng(static_cast<uint32_t>(camera) + 1);
  std::bernoulli_distribution dropped(drop_probability);
  const int64_t n = rig.num_frames();
  std::vector<std::optional<CameraPose>> poses(static_cast<size_t>(n));
  MonocularVo vo(rig.spec().cameras[camera], camera, VoOptions{});
  double sum2 = 0.0;
  int steps = 0;
  const CameraPose* previous = nullptr;
  int64_t previous_k = -1;
  for (int64_t k = 0; k < n; ++k) {
    if (dropped(rng)) continue;
    ++figures->frames;
    const VoResult r = vo.Process(rig.FrameTimeNs(k), rig.RenderFrame(camera, k));
    figures->relocalisations = r.relocalisations;
    if (!r.pose) continue;
    poses[static_cast<size_t>(k)] = *r.pose;
    ++figures->tracked;
    if (rig.spec().scene.moving_objects.count > 0) {
      CountObjectInliers(rig, camera, k, r.inlier_px, figures);
    }
    if (std::isnan(figures->first_pose_s)) figures->first_pose_s = rig.FrameStreamTime(k);
    const CameraPose& p = *poses[static_cast<size_t>(k)];
    if (previous != nullptr && previous->segment == p.segment) {
      const Pose a = rig.WorldFromCameraAt(camera, rig.FrameStreamTime(previous_k));
      const Pose b = rig.WorldFromCameraAt(camera, rig.FrameStreamTime(k));
      const Eigen::Quaterniond est = previous->pose.q.conjugate() * p.pose.q;
      const Eigen::Quaterniond truth = a.q.conjugate() * b.q;
      const double e = AngleDeg(est.conjugate() * truth);
      sum2 += e * e;
      ++steps;
    }
    previous = &p;
    previous_k = k;
  }
  int segments = 0, last = -1;
  for (const auto& p : poses) {
    if (p && p->segment != last) ++segments, last = p->segment;
  }
  figures->segments = segments;
  if (steps > 0) figures->rotation_rms_deg = std::sqrt(sum2 / steps);
  figures->inliers_on_objects /= std::max(1, figures->tracked);
  figures->inliers_near_objects /= std::max(1, figures->tracked);
  return poses;
}

// Per camera: the mean fraction of the pixels that show a moving object (where the frame differs
// from the same rig's without them) over every 10th frame, into `cover`, and the largest one
// into `cover_max`.
void MovingCover(const sim::SimulatedRig& rig, std::vector<double>* cover,
                 std::vector<double>* cover_max) {
  sim::SimulatedRigSpec still_spec = rig.spec();
  still_spec.scene.moving_objects.count = 0;
  auto still = sim::MakeSimulatedRig(still_spec);
  EXPECT_TRUE(still.ok()) << still.error();
  if (!still.ok()) return;
  for (int camera = 0; camera < rig.num_cameras(); ++camera) {
    double sum = 0.0, largest = 0.0;
    int n = 0;
    for (int64_t k = 0; k < rig.num_frames(); k += 10, ++n) {
      const cv::Mat a = rig.RenderFrame(camera, k);
      const double fraction =
          static_cast<double>(cv::countNonZero(a != still->RenderFrame(camera, k))) /
          static_cast<double>(a.total());
      sum += fraction;
      largest = std::max(largest, fraction);
    }
    cover->push_back(sum / std::max(1, n));
    cover_max->push_back(largest);
  }
}

CellResult RunCell(const sim::SimulatedRigSpec& base, const Cell& cell) {
  sim::SimulatedRigSpec spec = base;
  cell.apply(&spec);
  auto rig = sim::MakeSimulatedRig(spec);
  EXPECT_TRUE(rig.ok()) << rig.error();
  CellResult out;
  if (!rig.ok()) return out;
  if (spec.scene.moving_objects.count > 0) {
    MovingCover(*rig, &out.moving_cover, &out.moving_cover_max);
  }
  std::vector<std::vector<std::optional<CameraPose>>> poses;
  for (int camera = 0; camera < rig->num_cameras(); ++camera) {
    out.cameras.emplace_back();
    poses.push_back(RunVo(*rig, camera, cell.drop_probability, &out.cameras.back()));
  }
  RigEstimator estimator(spec.names, RigEstimatorOptions{});
  for (int64_t k = 0; k < rig->num_frames(); ++k) {
    std::vector<std::optional<CameraPose>> set;
    for (const auto& camera : poses) set.push_back(camera[static_cast<size_t>(k)]);
    if (!set[0] && !set[1]) continue;
    estimator.AddSet(rig->FrameTimeNs(k), set);
  }
  const RefinementJob job = estimator.MakeRefinementJob(0, true);
  if (job.start.solved()) estimator.ApplyRefinement(job, RefineWindow(job));
  out.slave = estimator.Estimate().rig.slaves[0];
  if (out.slave.solved()) {
    const Pose& truth = spec.master_from_camera[1];
    out.rotation_error_deg = AngleDeg(out.slave.estimate.q.conjugate() * truth.q);
    const double cosine = out.slave.estimate.C.normalized().dot(truth.C.normalized());
    out.direction_error_deg = std::acos(std::clamp(cosine, -1.0, 1.0)) * kDegPerRad;
  }
  return out;
}

TEST(VoRobustnessMatrix, EffectsCostAccuracyHonestly) {
  auto config =
      io::LoadRigConfig(std::string(RIGCAL_SOURCE_DIR) + "/config/sim_thesis_virtual.yaml");
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_TRUE(config->simulated_source.has_value());
  for (const std::string& file : kPhotoFiles) {
    if (RealPhoto(file).pixels.empty()) {
      RIGCAL_SKIP_MISSING() << "the real-photo cells need " << RealPhoto(file).name;
    }
  }
  sim::SimulatedRigSpec base = *config->simulated_source;
  base.realtime = false;
  if (const char* seed = std::getenv("RIGCAL_MATRIX_SEED")) {
    base.seed = std::stoull(seed);
    std::printf("\nseed %llu\n", static_cast<unsigned long long>(base.seed));
  }
  std::printf("\n%-15s %-14s | %-34s | %-34s | %-10s %9s %8s %7s %8s\n", "effect", "strength",
              "cam0: first s, tracked, seg, reloc, rot rms",
              "cam1: first s, tracked, seg, reloc, rot rms", "state", "rot deg", "σ deg", "rot/σ",
              "dir deg");
  const char* only = std::getenv("RIGCAL_MATRIX_EFFECT");
  for (const Cell& cell : Cells()) {
    if (only != nullptr && cell.effect != "none" && cell.effect.find(only) == std::string::npos) {
      continue;
    }
    const CellResult r = RunCell(base, cell);
    ASSERT_EQ(r.cameras.size(), 2u);
    std::string vo_text[2];
    for (int c = 0; c < 2; ++c) {
      const CameraFigures& f = r.cameras[c];
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%5.2f %5.1f%% %2d %3d %.4f", f.first_pose_s,
                    100.0 * f.tracked / std::max(1, f.frames), f.segments, f.relocalisations,
                    f.rotation_rms_deg);
      vo_text[c] = buf;
    }
    const double z = r.rotation_error_deg / r.slave.rot_std_deg;
    std::printf("%-15s %-14s | %-34s | %-34s | %-10s %9.4f %8.4f %7.2f %8.3f\n",
                cell.effect.c_str(), cell.strength.c_str(), vo_text[0].c_str(), vo_text[1].c_str(),
                std::string(ToString(r.slave.state)).c_str(), r.rotation_error_deg,
                r.slave.rot_std_deg, z, r.direction_error_deg);
    if (r.moving_cover.size() == 2) {
      std::printf(
          "%-15s %-14s   (moving objects cover %.1f%% of cam0's view, %.1f%% of cam1's; at most "
          "%.0f%%, %.0f%%)\n",
          "", "", 100.0 * r.moving_cover[0], 100.0 * r.moving_cover[1],
          100.0 * r.moving_cover_max[0], 100.0 * r.moving_cover_max[1]);
      std::printf(
          "%-15s %-14s   (VO pose inliers per frame on moving objects: cam0 %.3f, cam1 %.3f; "
          "within %.0f px of one: %.3f, %.3f)\n",
          "", "", r.cameras[0].inliers_on_objects, r.cameras[1].inliers_on_objects, kNearObjectPx,
          r.cameras[0].inliers_near_objects, r.cameras[1].inliers_near_objects);
    }
    if (cell.effect == "none") {
      for (const CameraFigures& f : r.cameras) {
        EXPECT_GE(f.tracked, f.frames * 9 / 10);
        EXPECT_EQ(f.segments, 1);
      }
      EXPECT_TRUE(r.slave.usable()) << r.slave.message;
    }
    if (r.slave.usable()) {
      EXPECT_LE(z, 3.0) << cell.effect << " " << cell.strength << ": " << r.slave.message;
    }
  }
}

}  // namespace
}  // namespace rigcal::vo
