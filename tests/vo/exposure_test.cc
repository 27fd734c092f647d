// SPDX-License-Identifier: Apache-2.0
// MonocularVo under exposure and gain changes (rendered room, support/room_sequence.h): every
// 15 frames the image brightness steps by a factor (auto-exposure), with a gentler flicker in
// between; the VO keeps tracking in one segment, as accurately as on the unchanged frames.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <map>
#include <vector>

#include "rigcal/vo/monocular_vo.h"
#include "support/ideal_cameras.h"
#include "support/relative_pose_errors.h"
#include "support/room_sequence.h"

namespace rigcal::vo {
namespace {

constexpr int kFrames = 140;
constexpr int64_t kFrameNs = 50'000'000;

struct ExposureRun {
  int segments = 0;
  int poses = 0;
  int first_pose = -1;
  double max_rotation_deg = 0.0;      // frame-to-frame relative rotation error
  double aligned_rms_fraction = 0.0;  // Sim(3)-aligned centre RMS / path length
};

// The exposure of frame k: steps of x1.6 and x0.55 every 15 frames (a camera's auto exposure
// catching up), and a 5 % flicker.
double Gain(int k) {
  const int step = k / 15;
  const double level = step % 3 == 1 ? 1.6 : (step % 3 == 2 ? 0.55 : 1.0);
  return level * (1.0 + 0.05 * std::sin(1.3 * k));
}

ExposureRun RunRoom(bool change_exposure) {
  const auto camera = support::PinholeWithFov(752, 480, 60.0);
  std::vector<Pose> poses;
  for (int k = 0; k < kFrames; ++k) poses.push_back(support::RoomPose(k));
  const sim::SimulatedRig rig = support::MakeRoomSequence(camera, poses).value();
  MonocularVo vo(camera, 0);
  std::map<int, std::map<int, Pose>> segments;
  std::map<int, Pose> truth;
  ExposureRun run;
  for (int k = 0; k < kFrames; ++k) {
    truth[k] = rig.WorldFromCameraAt(0, rig.FrameStreamTime(k));
    cv::Mat image = rig.RenderFrame(0, k);
    if (change_exposure) image.convertTo(image, CV_8U, Gain(k));  // saturates at 255
    const VoResult r = vo.Process(k * kFrameNs, image);
    if (r.segment_start) {
      segments[r.segment_start->segment][static_cast<int>(r.segment_start->t_ns / kFrameNs)] =
          r.segment_start->pose;
    }
    if (r.pose) {
      segments[r.pose->segment][k] = r.pose->pose;
      ++run.poses;
      if (run.first_pose < 0) run.first_pose = k;
    }
  }
  run.segments = static_cast<int>(segments.size());
  if (segments.empty()) return run;
  const std::map<int, Pose>& est = segments.begin()->second;
  for (const auto& e : support::RelativePoseErrors(est, truth, 1)) {
    run.max_rotation_deg = std::max(run.max_rotation_deg, e.rotation_deg);
  }
  Eigen::Matrix3Xd src(3, est.size()), dst(3, est.size());
  double path = 0.0;
  int i = 0;
  for (const auto& [k, pose] : est) {
    src.col(i) = pose.C;
    dst.col(i) = truth.at(k).C;
    if (i > 0) path += (dst.col(i) - dst.col(i - 1)).norm();
    ++i;
  }
  const Eigen::Matrix4d sim = Eigen::umeyama(src, dst, true);
  double err2 = 0.0;
  for (int j = 0; j < i; ++j) {
    err2 += (sim.block<3, 3>(0, 0) * src.col(j) + sim.block<3, 1>(0, 3) - dst.col(j)).squaredNorm();
  }
  run.aligned_rms_fraction = std::sqrt(err2 / i) / path;
  return run;
}

TEST(Exposure, StepsAndFlickerAreTolerated) {
  const ExposureRun steady = RunRoom(false);
  const ExposureRun changing = RunRoom(true);
  for (const auto& [label, run] : {std::pair{"steady", steady}, std::pair{"changing", changing}}) {
    std::printf(
        "%s exposure: %d segment(s), first pose at frame %d, %d poses, frame-to-frame rotation "
        "error max %.4f deg, aligned centre RMS %.3f %% of the path\n",
        label, run.segments, run.first_pose, run.poses, run.max_rotation_deg,
        100.0 * run.aligned_rms_fraction);
  }
  EXPECT_EQ(changing.segments, 1);
  // A pose for every frame from the first on, as with a steady exposure.
  EXPECT_EQ(changing.poses, kFrames - changing.first_pose);
  EXPECT_LE(changing.first_pose, steady.first_pose + 5);
  // The accuracy targets of the room tests.
  EXPECT_LE(changing.max_rotation_deg, 0.1);
  EXPECT_LE(changing.aligned_rms_fraction, 0.01);
}

}  // namespace
}  // namespace rigcal::vo
