// SPDX-License-Identifier: Apache-2.0
// MonocularVo relocalisation on rendered sequences of the textured room (support/room_sequence.h):
// frames removed (gaps of 1, 5, 10 and 30 frames at 20 Hz), the lens covered for 0.5 s (black
// frames), a shaken camera, and a loss that outlasts relocalisation_timeout_s. The VO must go on
// in the same scale segment after the interruption, with the motion across it as accurate as
// between consecutive frames, and open a new segment only after the timeout.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <functional>
#include <map>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/vo/monocular_vo.h"
#include "support/ideal_cameras.h"
#include "support/relative_pose_errors.h"
#include "support/room_sequence.h"

namespace rigcal::vo {
namespace {

constexpr int64_t kFrameNs = 50'000'000;  // 20 Hz

struct RoomRun {
  std::vector<int> fed;                         // frame index of every Process call
  std::vector<VoResult> results;                // one per call
  std::map<int, std::map<int, Pose>> segments;  // segment -> frame -> pose
  std::map<int, Pose> truth;                    // frame -> true world_from_camera
};

// Frames 0 .. n - 1 of a camera moving by `pose_of` in the room, rendered once.
struct RenderedRoom {
  std::shared_ptr<const camera::CameraModel> camera;
  std::vector<cv::Mat> images;
  std::map<int, Pose> truth;
};

RenderedRoom Render(int frames, const std::function<Pose(int)>& pose_of) {
  RenderedRoom room;
  room.camera = support::PinholeWithFov(752, 480, 60.0);
  std::vector<Pose> poses;
  for (int k = 0; k < frames; ++k) poses.push_back(pose_of(k));
  const sim::SimulatedRig rig = support::MakeRoomSequence(room.camera, poses).value();
  for (int k = 0; k < frames; ++k) {
    room.images.push_back(rig.RenderFrame(0, k));
    room.truth[k] = rig.WorldFromCameraAt(0, rig.FrameStreamTime(k));
  }
  return room;
}

// The smooth room motion (support::RoomPose), rendered once for all tests.
const RenderedRoom& SmoothRoom() {
  static const RenderedRoom room = Render(160, support::RoomPose);
  return room;
}

// Feeds the frames k of `room` with keep(k) to a VO (frame k at k * 50 ms; a black image where
// black(k)).
RoomRun RunRoom(const RenderedRoom& room, const std::function<bool(int)>& keep,
                const std::function<bool(int)>& black, VoOptions options = {}) {
  MonocularVo vo(room.camera, 0, options);
  RoomRun run;
  run.truth = room.truth;
  for (int k = 0; k < static_cast<int>(room.images.size()); ++k) {
    if (!keep(k)) continue;
    const cv::Mat image = black(k) ? cv::Mat::zeros(room.images[k].size(), CV_8UC1)
                                   : room.images[static_cast<size_t>(k)];
    const VoResult r = vo.Process(k * kFrameNs, image);
    if (r.segment_start) {
      run.segments[r.segment_start->segment][static_cast<int>(r.segment_start->t_ns / kFrameNs)] =
          r.segment_start->pose;
    }
    if (r.pose) run.segments[r.pose->segment][k] = r.pose->pose;
    run.fed.push_back(k);
    run.results.push_back(r);
  }
  return run;
}

// Sim(3) scale of a segment (truth units per VO unit) from its poses' centres.
double SegmentScale(const std::map<int, Pose>& poses, const std::map<int, Pose>& truth) {
  Eigen::Matrix3Xd src(3, poses.size()), dst(3, poses.size());
  int i = 0;
  for (const auto& [k, pose] : poses) {
    src.col(i) = pose.C;
    dst.col(i++) = truth.at(k).C;
  }
  return Eigen::umeyama(src, dst, true).block<3, 1>(0, 0).norm();
}

// The motion from the last pose before `gap_start` to the first pose from `gap_end` on, against
// the truth; its scale relative to the segment's.
support::RelativePoseError AcrossGap(const RoomRun& run, int gap_start, int gap_end) {
  const std::map<int, Pose>& poses = run.segments.begin()->second;
  const auto before = std::prev(poses.lower_bound(gap_start));
  const auto after = poses.lower_bound(gap_end);
  EXPECT_NE(after, poses.end());
  support::RelativePoseError e = support::CompareRelativeMotion(
      before->second, after->second, run.truth.at(before->first), run.truth.at(after->first));
  e.a = before->first;
  e.b = after->first;
  e.scale /= SegmentScale(poses, run.truth);
  return e;
}

int Relocalisations(const RoomRun& run) { return run.results.back().relocalisations; }

auto Always = [](int) { return true; };
auto Never = [](int) { return false; };

// Gaps in the frames: the VO relocalises (or tracks through a short gap) in segment 0; the motion
// across the gap is as accurate as the VO's frame-to-frame motion (0.1 degrees, the accuracy
// target of the room tests) and its scale is the segment's within 2 %.
TEST(Relocalisation, GapsOfOneToThirtyFramesKeepTheSegment) {
  for (const int gap : {1, 5, 10, 30}) {
    SCOPED_TRACE("gap of " + std::to_string(gap) + " frames");
    const int gap_start = 70;
    const RoomRun run = RunRoom(
        SmoothRoom(), [&](int k) { return k < gap_start || k >= gap_start + gap; }, Never);
    ASSERT_EQ(run.segments.size(), 1u);
    const auto error = AcrossGap(run, gap_start, gap_start + gap);
    std::printf(
        "gap %2d frames: %d relocalisation(s); across frames %d-%d rotation error %.4f deg, "
        "direction error %.3f deg, scale %.4f of the segment's\n",
        gap, Relocalisations(run), error.a, error.b, error.rotation_deg, error.direction_deg,
        error.scale);
    EXPECT_EQ(error.a, gap_start - 1);
    EXPECT_EQ(error.b, gap_start + gap);
    EXPECT_LE(error.rotation_deg, 0.1);
    EXPECT_LE(error.direction_deg, 2.0);
    EXPECT_NEAR(error.scale, 1.0, 0.02);
    if (gap == 30) {
      EXPECT_GE(Relocalisations(run), 1);  // shorter gaps may be tracked through
    }
    int poses_after = 0;
    for (const VoResult& r : run.results) poses_after += r.pose && r.pose->t_ns > 100 * kFrameNs;
    EXPECT_EQ(poses_after, 59);  // every frame after the gap has a pose
  }
}

// The lens covered for 0.5 s: tracking is lost on the first black frame, the VO relocalises on
// the first frame after, in segment 0, and says so.
TEST(Relocalisation, CoveredLensForHalfASecond) {
  const int cover_start = 70;
  const int cover_end = cover_start + 10;
  const RoomRun run =
      RunRoom(SmoothRoom(), Always, [&](int k) { return k >= cover_start && k < cover_end; });
  ASSERT_EQ(run.segments.size(), 1u);
  for (size_t i = 0; i < run.fed.size(); ++i) {
    const int k = run.fed[i];
    if (k >= cover_start && k < cover_end) {
      EXPECT_EQ(run.results[i].state, VoState::kLost) << "frame " << k;
      EXPECT_FALSE(run.results[i].pose.has_value());
    }
    if (k == cover_end) {
      EXPECT_TRUE(run.results[i].relocalised) << run.results[i].message;
      EXPECT_EQ(run.results[i].relocalisations, 1);
      EXPECT_EQ(run.results[i].state, VoState::kTracking);
    }
  }
  EXPECT_NE(run.results[static_cast<size_t>(cover_start)].message.find("tracking lost"),
            std::string::npos)
      << run.results[static_cast<size_t>(cover_start)].message;
  const auto error = AcrossGap(run, cover_start, cover_end);
  std::printf(
      "covered: across frames %d-%d rotation error %.4f deg, direction error %.3f deg, "
      "scale %.4f\n",
      error.a, error.b, error.rotation_deg, error.direction_deg, error.scale);
  EXPECT_LE(error.rotation_deg, 0.1);
  EXPECT_LE(error.direction_deg, 2.0);
  EXPECT_NEAR(error.scale, 1.0, 0.02);
  EXPECT_EQ(Relocalisations(run), 1);
}

// A camera shaken for one second (rotations of up to 3 degrees from frame to frame on top of
// the smooth motion): it stays in segment 0 and its poses after the shaking are accurate.
TEST(Relocalisation, ShakenCameraStaysInItsSegment) {
  const auto shaken = [](int k) {
    Pose pose = support::RoomPose(k);
    if (k >= 60 && k < 80) {
      const double t = (k - 60) / support::kRoomFrameRateHz;
      const double amplitude = 3.0 * M_PI / 180.0 * std::sin(2.0 * M_PI * 7.0 * t);
      pose.q = pose.q * AxisAngle(Eigen::Vector3d(1.0, 0.7, 0.2), amplitude);
    }
    return pose;
  };
  const RoomRun run = RunRoom(Render(140, shaken), Always, Never);
  ASSERT_EQ(run.segments.size(), 1u);
  const std::map<int, Pose>& poses = run.segments.begin()->second;
  int after = 0;
  for (const auto& [k, pose] : poses) after += k >= 80;
  EXPECT_GE(after, 55);
  const auto error = AcrossGap(run, 60, 80);
  std::printf(
      "shaken: %d relocalisation(s), %zu poses; across frames %d-%d rotation error %.4f "
      "deg, scale %.4f\n",
      Relocalisations(run), poses.size(), error.a, error.b, error.rotation_deg, error.scale);
  EXPECT_LE(error.rotation_deg, 0.1);
  EXPECT_NEAR(error.scale, 1.0, 0.02);
}

// Covered for longer than relocalisation_timeout_s: the segment ends once the timeout has
// passed (and not before), the reason is in the message, and a new initialisation opens
// segment 1 on the frames after.
TEST(Relocalisation, ANewSegmentOnlyAfterTheTimeout) {
  VoOptions options;
  options.relocalisation_timeout_s = 1.0;
  const int cover_start = 60;
  const int cover_end = 90;  // 1.5 s
  const RoomRun run = RunRoom(
      SmoothRoom(), Always, [&](int k) { return k >= cover_start && k < cover_end; }, options);
  ASSERT_EQ(run.segments.size(), 2u);
  EXPECT_EQ(run.segments.begin()->first, 0);
  EXPECT_EQ(run.segments.rbegin()->first, 1);
  int gave_up = -1;
  for (size_t i = 0; i < run.fed.size(); ++i) {
    if (run.results[i].message.find("relocalisation failed for") != std::string::npos) {
      gave_up = run.fed[i];
      break;
    }
  }
  // The first attempt is at frame 60; 1 s later is frame 80, the first frame beyond it 81.
  EXPECT_EQ(gave_up, cover_start + 21);
  EXPECT_EQ(Relocalisations(run), 0);
  EXPECT_GT(run.segments.rbegin()->second.begin()->first, cover_end - 1);
}

TEST(Relocalisation, OptionsAreChecked) {
  VoOptions options;
  options.relocalisation_timeout_s = -1.0;
  EXPECT_EQ(options.Check().message(), "relocalisation_timeout_s: must be >= 0");
  options = VoOptions{};
  options.relocalisation_ratio = 1.5;
  EXPECT_EQ(options.Check().message(), "relocalisation_ratio: must be in (0, 1]");
}

}  // namespace
}  // namespace rigcal::vo
