// MonocularVo on the simulated rig's rendered sequences (drivers/simulated_rig.h) of the
// example configs: the thesis 5.4 virtual scene (two 60-degree pinhole cameras, 468 frames) and
// the spherical rig of thesis 5.7 (two 186-degree fisheyes back to back). Per camera and scale
// segment: frame-to-frame rotation error <= 0.1 degrees and Sim(3)-aligned centre error <= 1 %
// of the path length. Slow (label eval): `ctest -L eval -R vo/`.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <map>

#include "rigcal/drivers/simulated_rig.h"
#include "rigcal/tools/rig_config.h"
#include "rigcal/vo/camera_spec.h"
#include "rigcal/vo/monocular_vo.h"

namespace rigcal::vo {
namespace {

struct CameraRun {
  std::map<int, std::map<int64_t, Pose>> segments;  // segment -> frame -> VO pose
  int frames = 0;
  int tracked = 0;
  double median_ms = 0.0;
};

CameraRun RunCamera(const drivers::SimulatedRig& rig, int camera, int64_t frames) {
  CameraRun run;
  MonocularVo vo(rig.spec().cameras[camera], camera);
  std::map<int64_t, int64_t> frame_of;  // t_ns -> frame index
  std::vector<double> ms;
  for (int64_t k = 0; k < frames; ++k) {
    const int64_t t_ns = rig.FrameTimeNs(k);
    frame_of[t_ns] = k;
    const VoResult r = vo.Process(t_ns, rig.RenderFrame(camera, k));
    ms.push_back(r.processing_ms);
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
  std::sort(ms.begin(), ms.end());
  run.median_ms = ms[ms.size() / 2];
  return run;
}

void CheckSegment(const drivers::SimulatedRig& rig, int camera, const std::map<int64_t, Pose>& est,
                  const std::string& label) {
  std::vector<int64_t> frames;
  for (const auto& [k, pose] : est) frames.push_back(k);
  ASSERT_GE(frames.size(), 3u) << label;
  auto truth = [&](int64_t k) { return rig.CameraPoseAt(camera, rig.FrameStreamTime(k)); };
  double max_rot = 0.0, path = 0.0, sum2 = 0.0;
  int64_t max_frame = -1;
  std::vector<double> errors;
  Eigen::Matrix3Xd src(3, frames.size()), dst(3, frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    src.col(i) = est.at(frames[i]).C;
    dst.col(i) = truth(frames[i]).C;
    if (i == 0) continue;
    const Eigen::Matrix3d e = est.at(frames[i - 1]).R().transpose() * est.at(frames[i]).R();
    const Eigen::Matrix3d t = truth(frames[i - 1]).R().transpose() * truth(frames[i]).R();
    const double err = Eigen::AngleAxisd(e.transpose() * t).angle() * 180.0 / M_PI;
    if (err > max_rot) max_frame = frames[i];
    max_rot = std::max(max_rot, err);
    sum2 += err * err;
    errors.push_back(err);
    path += (dst.col(i) - dst.col(i - 1)).norm();
  }
  const Eigen::Matrix4d sim = Eigen::umeyama(src, dst, true);
  double err2 = 0.0;
  for (size_t i = 0; i < frames.size(); ++i) {
    err2 += (sim.block<3, 3>(0, 0) * src.col(i) + sim.block<3, 1>(0, 3) - dst.col(i)).squaredNorm();
  }
  const double rms = std::sqrt(err2 / frames.size());
  std::sort(errors.begin(), errors.end());
  std::printf(
      "%s: %zu poses, frame-to-frame rotation error max %.4f deg (frame %lld) p99 %.4f "
      "rms %.4f deg, aligned centre rms %.4f m = %.3f %% of path %.2f m\n",
      label.c_str(), frames.size(), max_rot, static_cast<long long>(max_frame),
      errors[errors.size() * 99 / 100], std::sqrt(sum2 / errors.size()), rms, 100.0 * rms / path,
      path);
  EXPECT_LE(max_rot, 0.1) << label;
  EXPECT_LE(rms, 0.01 * path) << label;
}

void EvaluateConfig(const std::string& file, int64_t max_frames) {
  const std::string path = std::string(RIGCAL_SOURCE_DIR) + "/config/" + file;
  auto config = tools::LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.error();
  ASSERT_TRUE(config->simulated_source.has_value());
  drivers::SimulatedRigSpec spec = *config->simulated_source;
  spec.realtime = false;
  auto rig = drivers::MakeSimulatedRig(spec);
  ASSERT_TRUE(rig.ok()) << rig.error();
  const int64_t frames = std::min(rig->num_frames(), max_frames);
  for (int camera = 0; camera < rig->num_cameras(); ++camera) {
    const CameraRun run = RunCamera(*rig, camera, frames);
    std::printf("%s camera %d: %d of %d frames with a pose, %zu segment(s), median %.2f ms\n",
                file.c_str(), camera, run.tracked, run.frames, run.segments.size(), run.median_ms);
    EXPECT_GE(run.tracked, run.frames * 8 / 10) << file << " camera " << camera;
    for (const auto& [segment, poses] : run.segments) {
      if (poses.size() < 10) continue;  // a segment cut short by the end of the sequence
      CheckSegment(
          *rig, camera, poses,
          file + " camera " + std::to_string(camera) + " segment " + std::to_string(segment));
    }
  }
}

TEST(SimulatedRigVo, ThesisVirtualScene) { EvaluateConfig("sim_thesis_virtual.yaml", 468); }

TEST(SimulatedRigVo, SphericalFisheyes186) { EvaluateConfig("sim_spherical.yaml", 300); }

}  // namespace
}  // namespace rigcal::vo
