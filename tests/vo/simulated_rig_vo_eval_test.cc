// SPDX-License-Identifier: Apache-2.0
// MonocularVo on the simulated rig's rendered sequences (sim/simulated_rig.h) of the
// example configs, one camera at a time in one thread (deterministic, no pipeline): the thesis
// 5.4 virtual scene (two 60-degree pinhole cameras, 468 frames), the spherical rig of thesis 5.7
// (two 186-degree fisheyes back to back), the sewer of thesis 5.6 (two fisheyes in a 60 cm
// pipe) and the 4-camera car rig. Per camera and scale segment: frame-to-frame rotation error
// <= 0.1 degrees and Sim(3)-aligned centre error <= 1 % of the path length (issue 4, section
// 6). Also printed, to locate the error of a calibration: the rotation drift (orientation error
// against the segment's reference frame), the scale drift inside the segment (Sim(3) scale of
// windows of the segment against the whole segment's) and the time per frame.
// Slow (label eval): `ctest -L eval -R vo/`. With RIGCAL_VO_EVAL_POSES_DIR set, the VO poses of
// every camera are also written there as `<config>/<camera>.txt` (rigcal native format with
// the segment column, for `rigcal solve`) next to the true poses `<config>/<camera>_truth.txt`;
// RIGCAL_VO_EVAL_RENDER_BLOCK overrides the configs' render_block (1: exact ray casting) and
// RIGCAL_VO_EVAL_OPTIONS VoOptions fields ("max_features=300,ba_window=8").

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "rigcal/base/robust_statistics.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/sim/simulated_rig.h"
#include "rigcal/vo/monocular_vo.h"
#include "vo_eval_options.h"

namespace rigcal::vo {
namespace {

struct CameraRun {
  std::map<int, std::map<int64_t, Pose>> segments;  // segment -> frame -> VO pose
  int frames = 0;
  int tracked = 0;
  double median_ms = 0.0;
};

CameraRun RunCamera(const sim::SimulatedRig& rig, int camera, int64_t frames) {
  CameraRun run;
  MonocularVo vo(rig.spec().cameras[camera], camera, EvalOptions());
  std::map<int64_t, int64_t> frame_of;  // t_ns -> frame index
  std::vector<double> ms;
  for (int64_t k = 0; k < frames; ++k) {
    const int64_t t_ns = rig.FrameTimeNs(k);
    frame_of[t_ns] = k;
    const VoResult r = vo.Process(t_ns, rig.RenderFrame(camera, k));
    ms.push_back(r.processing_ms);
    if (std::getenv("RIGCAL_VO_EVAL_VERBOSE") != nullptr) {
      std::printf("frame %lld: %s tracks %d inliers %d%s %.2f ms %s\n", static_cast<long long>(k),
                  ToString(r.state).c_str(), r.tracked_features, r.inliers,
                  r.keyframe ? " keyframe" : "", r.processing_ms, r.message.c_str());
    }
    if (r.segment_start) {
      run.segments[r.segment_start->segment][frame_of.at(r.segment_start->t_ns)] =
          r.segment_start->pose;
    }
    if (r.pose) {
      run.segments[r.pose->segment][k] = r.pose->pose;
      ++run.tracked;
    }
    ++run.frames;
  }
  run.median_ms = UpperMedian(std::move(ms));
  return run;
}

double AngleDeg(const Eigen::Matrix3d& r) { return Eigen::AngleAxisd(r).angle() * 180.0 / M_PI; }

// Sim(3) scale of the estimated centres src onto the true ones dst (columns i0 .. i0 + n - 1).
double Sim3Scale(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, int i0, int n) {
  const Eigen::Matrix4d sim = Eigen::umeyama(src.middleCols(i0, n), dst.middleCols(i0, n), true);
  return sim.block<3, 1>(0, 0).norm();
}

void CheckSegment(const sim::SimulatedRig& rig, int camera, const std::map<int64_t, Pose>& est,
                  const std::string& label) {
  std::vector<int64_t> frames;
  for (const auto& [k, pose] : est) frames.push_back(k);
  ASSERT_GE(frames.size(), 3u) << label;
  auto truth = [&](int64_t k) { return rig.WorldFromCameraAt(camera, rig.FrameStreamTime(k)); };
  const Pose reference = truth(frames.front());
  double max_rot = 0.0, path = 0.0, sum2 = 0.0, max_drift = 0.0;
  int64_t max_frame = -1;
  std::vector<double> errors;
  Eigen::Matrix3Xd src(3, frames.size()), dst(3, frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    src.col(i) = est.at(frames[i]).C;
    dst.col(i) = truth(frames[i]).C;
    // Orientation error in the segment's reference frame (VO rotation drift).
    const Eigen::Matrix3d true_in_reference = reference.R().transpose() * truth(frames[i]).R();
    max_drift =
        std::max(max_drift, AngleDeg(est.at(frames[i]).R().transpose() * true_in_reference));
    if (i == 0) continue;
    const Eigen::Matrix3d e = est.at(frames[i - 1]).R().transpose() * est.at(frames[i]).R();
    const Eigen::Matrix3d t = truth(frames[i - 1]).R().transpose() * truth(frames[i]).R();
    const double err = AngleDeg(e.transpose() * t);
    if (err > max_rot) max_frame = frames[i];
    max_rot = std::max(max_rot, err);
    sum2 += err * err;
    errors.push_back(err);
    path += (dst.col(i) - dst.col(i - 1)).norm();
  }
  const int n = static_cast<int>(frames.size());
  const Eigen::Matrix4d sim = Eigen::umeyama(src, dst, true);
  double err2 = 0.0;
  for (int i = 0; i < n; ++i) {
    err2 += (sim.block<3, 3>(0, 0) * src.col(i) + sim.block<3, 1>(0, 3) - dst.col(i)).squaredNorm();
  }
  const double rms = std::sqrt(err2 / n);
  // Scale drift: Sim(3) scale of six consecutive windows relative to the whole segment's.
  const double scale = sim.block<3, 1>(0, 0).norm();
  std::string windows;
  double min_window = 1e9, max_window = 0.0;
  const int w = std::max(20, n / 6);
  for (int i0 = 0; i0 + w <= n; i0 += w) {
    const double s = Sim3Scale(src, dst, i0, w) / scale;
    min_window = std::min(min_window, s);
    max_window = std::max(max_window, s);
    char buf[16];
    std::snprintf(buf, sizeof(buf), " %.3f", s);
    windows += buf;
  }
  std::sort(errors.begin(), errors.end());
  std::printf(
      "%s: %zu poses, frame-to-frame rotation error max %.4f deg (frame %lld) p99 %.4f "
      "rms %.4f deg, rotation drift max %.3f deg, aligned centre rms %.4f m = %.3f %% of path "
      "%.2f m, window scales / segment scale%s (spread %.2f %%)\n",
      label.c_str(), frames.size(), max_rot, static_cast<long long>(max_frame),
      errors[errors.size() * 99 / 100], std::sqrt(sum2 / errors.size()), max_drift, rms,
      100.0 * rms / path, path, windows.c_str(), 100.0 * (max_window - min_window));
  EXPECT_LE(max_rot, 0.1) << label;
  EXPECT_LE(rms, 0.01 * path) << label;
}

// Writes the VO poses (all segments) and the true poses of `camera` when
// RIGCAL_VO_EVAL_POSES_DIR is set.
void MaybeWritePoses(const sim::SimulatedRig& rig, int camera, const CameraRun& run,
                     const std::string& stem) {
  const char* dir = std::getenv("RIGCAL_VO_EVAL_POSES_DIR");
  if (dir == nullptr || *dir == '\0') return;
  const std::string base = std::string(dir) + "/" + stem;
  std::filesystem::create_directories(std::filesystem::path(base).parent_path());
  TimedTrajectory est, truth;
  std::map<int64_t, std::pair<Pose, int>> by_frame;
  for (const auto& [segment, poses] : run.segments) {
    for (const auto& [k, pose] : poses) by_frame.emplace(k, std::make_pair(pose, segment));
  }
  const Pose first = rig.WorldFromCameraAt(camera, rig.FrameStreamTime(0));
  for (const auto& [k, entry] : by_frame) {
    est.t_ns.push_back(rig.FrameTimeNs(k));
    est.poses.push_back(entry.first);
    est.segment.push_back(entry.second);
  }
  for (int64_t k = 0; k < run.frames; ++k) {
    const Pose p = rig.WorldFromCameraAt(camera, rig.FrameStreamTime(k));
    Pose local;
    local.q = Eigen::Quaterniond(first.R().transpose() * p.R());
    local.C = first.R().transpose() * (p.C - first.C);
    truth.t_ns.push_back(rig.FrameTimeNs(k));
    truth.poses.push_back(local);
  }
  EXPECT_TRUE(io::WriteTrajectoryNative(base + ".txt", est).ok());
  EXPECT_TRUE(io::WriteTrajectoryNative(base + "_truth.txt", truth).ok());
}

void EvaluateConfig(const std::string& file, int64_t max_frames) {
  const std::string path = std::string(RIGCAL_SOURCE_DIR) + "/config/" + file;
  auto config = io::LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_TRUE(config->simulated_source.has_value());
  sim::SimulatedRigSpec spec = *config->simulated_source;
  spec.realtime = false;
  if (const char* block = std::getenv("RIGCAL_VO_EVAL_RENDER_BLOCK")) {
    spec.render_block = std::atoi(block);  // 1 = exact ray casting, to judge the renderer
  }
  auto rig = sim::MakeSimulatedRig(spec);
  ASSERT_TRUE(rig.ok()) << rig.error();
  const int64_t frames = std::min(rig->num_frames(), max_frames);
  const std::string config_stem = std::filesystem::path(file).stem().string();
  for (int camera = 0; camera < rig->num_cameras(); ++camera) {
    const CameraRun run = RunCamera(*rig, camera, frames);
    std::printf("%s camera %d: %d of %d frames with a pose, %zu segment(s), median %.2f ms\n",
                file.c_str(), camera, run.tracked, run.frames, run.segments.size(), run.median_ms);
    EXPECT_GE(run.tracked, run.frames * 8 / 10) << file << " camera " << camera;
    MaybeWritePoses(*rig, camera, run, config_stem + "/" + spec.names[camera]);
    for (const auto& [segment, poses] : run.segments) {
      if (poses.size() < 10) continue;  // a segment cut short by the end of the sequence
      CheckSegment(
          *rig, camera, poses,
          file + " camera " + std::to_string(camera) + " segment " + std::to_string(segment));
    }
  }
}

TEST(SimulatedRigVo, ThesisVirtualScene) { EvaluateConfig("sim_thesis_virtual.yaml", 468); }

TEST(SimulatedRigVo, SphericalFisheyes186) { EvaluateConfig("sim_spherical.yaml", 480); }

TEST(SimulatedRigVo, SewerPipeFisheyes) { EvaluateConfig("sim_sewer.yaml", 480); }

TEST(SimulatedRigVo, Surround4Car) { EvaluateConfig("sim_surround4.yaml", 800); }

}  // namespace
}  // namespace rigcal::vo
