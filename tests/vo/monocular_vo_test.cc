// SPDX-License-Identifier: Apache-2.0
// MonocularVo on image sequences of a camera moving through the textured room of the simulated
// rig (support/room_sequence.h: drivers' renderer, rigcal_camera's ideal pinhole 60 degrees and
// equidistant 186-degree fisheye), pure rotation, a static camera, blank frames (tracking loss
// -> relocalisation in the same segment) and bad input.

#include "rigcal/vo/monocular_vo.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <map>

#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/camera/camera_spec.h"
#include "support/ideal_cameras.h"
#include "support/room_sequence.h"

namespace rigcal::vo {
namespace {

using support::EquidistantWithFov;
using support::PinholeWithFov;
using support::RoomPose;

constexpr int64_t kFrameNs = 50'000'000;  // 20 Hz

struct Sequence {
  std::vector<int64_t> t_ns;
  std::vector<Eigen::Matrix3d> R;  // world_from_cam, truth
  std::vector<Eigen::Vector3d> C;
  std::vector<VoResult> results;
};

// Runs the VO over `frames` frames rendered in the room; `pose_of(k)` gives the pose
// (world_from_camera) of frame k and `blank(k)` says which frames are replaced by a uniform
// grey image.
template <typename PoseOf, typename Blank>
Sequence RunSequence(const std::shared_ptr<const camera::CameraModel>& camera, int frames,
                     PoseOf pose_of, Blank blank, VoOptions options = {}) {
  std::vector<Pose> poses;
  for (int k = 0; k < frames; ++k) poses.push_back(pose_of(k));
  const sim::SimulatedRig rig = support::MakeRoomSequence(camera, poses).value();
  MonocularVo vo(camera, 0, options);
  Sequence s;
  for (int k = 0; k < frames; ++k) {
    const Pose truth = rig.WorldFromCameraAt(0, rig.FrameStreamTime(k));
    cv::Mat image = blank(k) ? cv::Mat(camera->height(), camera->width(), CV_8UC1, cv::Scalar(128))
                             : rig.RenderFrame(0, k);
    s.t_ns.push_back(k * kFrameNs);
    s.R.push_back(truth.R());
    s.C.push_back(truth.C);
    s.results.push_back(vo.Process(k * kFrameNs, image));
  }
  return s;
}

struct SegmentErrors {
  int poses = 0;
  double max_relative_rotation_deg = 0.0;  // frame to frame
  double rms_relative_rotation_deg = 0.0;
  double aligned_rms = 0.0;  // after Sim(3) alignment, truth units
  double path_length = 0.0;  // truth units
  double scale = 0.0;        // truth units per VO unit
};

// Errors of the poses of one segment (including its reference frame) against the truth.
SegmentErrors Evaluate(const Sequence& s, int segment) {
  std::map<int64_t, Pose> est;
  for (const VoResult& r : s.results) {
    if (r.segment_start && r.segment_start->segment == segment) {
      est[r.segment_start->t_ns] = r.segment_start->pose;
    }
    if (r.pose && r.pose->segment == segment) est[r.pose->t_ns] = r.pose->pose;
  }
  SegmentErrors e;
  std::vector<int> frames;
  for (const auto& [t, pose] : est) frames.push_back(static_cast<int>(t / kFrameNs));
  e.poses = static_cast<int>(frames.size());
  if (frames.size() < 3) return e;
  // Frame-to-frame rotation errors (consecutive VO poses).
  double sum2 = 0.0;
  int n = 0;
  for (size_t i = 1; i < frames.size(); ++i) {
    const int a = frames[i - 1], b = frames[i];
    const Eigen::Matrix3d est_rel = est[a * kFrameNs].R().transpose() * est[b * kFrameNs].R();
    const Eigen::Matrix3d true_rel = s.R[a].transpose() * s.R[b];
    const double err = Eigen::AngleAxisd(est_rel.transpose() * true_rel).angle() * 180.0 / M_PI;
    e.max_relative_rotation_deg = std::max(e.max_relative_rotation_deg, err);
    sum2 += err * err;
    ++n;
  }
  e.rms_relative_rotation_deg = std::sqrt(sum2 / n);
  // Sim(3) alignment of the estimated centres to the true ones (Umeyama).
  Eigen::Matrix3Xd src(3, frames.size()), dst(3, frames.size());
  for (size_t i = 0; i < frames.size(); ++i) {
    src.col(i) = est[frames[i] * kFrameNs].C;
    dst.col(i) = s.C[frames[i]];
    if (i > 0) e.path_length += (s.C[frames[i]] - s.C[frames[i - 1]]).norm();
  }
  const Eigen::Matrix4d sim = Eigen::umeyama(src, dst, true);
  e.scale = sim.block<3, 1>(0, 0).norm();
  double err2 = 0.0;
  for (size_t i = 0; i < frames.size(); ++i) {
    const Eigen::Vector3d aligned = sim.block<3, 3>(0, 0) * src.col(i) + sim.block<3, 1>(0, 3);
    err2 += (aligned - dst.col(i)).squaredNorm();
  }
  e.aligned_rms = std::sqrt(err2 / frames.size());
  return e;
}

void Report(const char* name, const Sequence& s, const SegmentErrors& e) {
  std::vector<double> ms;
  for (const VoResult& r : s.results) ms.push_back(r.processing_ms);
  std::printf(
      "%s: %d poses, frame-to-frame rotation error max %.4f deg rms %.4f deg, Sim(3)-aligned "
      "centre rms %.4f = %.3f %% of path %.3f; median %.2f ms/frame (wall clock, depends on "
      "machine load)\n",
      name, e.poses, e.max_relative_rotation_deg, e.rms_relative_rotation_deg, e.aligned_rms,
      100.0 * e.aligned_rms / e.path_length, e.path_length, UpperMedian(ms));
}

int FirstTracking(const Sequence& s) {
  for (size_t k = 0; k < s.results.size(); ++k) {
    if (s.results[k].state == VoState::kTracking) return static_cast<int>(k);
  }
  return -1;
}

auto NoBlank = [](int) { return false; };

TEST(MonocularVo, PinholeRoomSequenceMeetsAccuracyTargets) {
  const auto camera = PinholeWithFov(752, 480, 60.0);
  const Sequence s = RunSequence(camera, 160, RoomPose, NoBlank);
  const int first = FirstTracking(s);
  ASSERT_GE(first, 1);
  EXPECT_LT(first, 40);
  for (size_t k = first; k < s.results.size(); ++k) {
    EXPECT_EQ(s.results[k].state, VoState::kTracking)
        << "frame " << k << ": " << s.results[k].message;
    ASSERT_TRUE(s.results[k].pose.has_value());
    EXPECT_EQ(s.results[k].pose->segment, 0);
    EXPECT_EQ(s.results[k].pose->camera, 0);
    EXPECT_EQ(s.results[k].pose->t_ns, s.t_ns[k]);
    EXPECT_GT(s.results[k].pose->quality, 0.0);
  }
  ASSERT_TRUE(s.results[first].segment_start.has_value());
  EXPECT_LT(s.results[first].segment_start->t_ns, s.t_ns[first]);
  EXPECT_NEAR(s.results[first].pose->pose.C.norm(), 1.0, 1e-9);  // ||C^1|| = 1
  const SegmentErrors e = Evaluate(s, 0);
  Report("pinhole 60 deg", s, e);
  EXPECT_LE(e.max_relative_rotation_deg, 0.1);
  EXPECT_LE(e.aligned_rms, 0.01 * e.path_length);
}

TEST(MonocularVo, Fisheye186RoomSequenceMeetsAccuracyTargets) {
  const auto camera = EquidistantWithFov(640, 640, 186.0);
  const Sequence s = RunSequence(camera, 140, RoomPose, NoBlank);
  const int first = FirstTracking(s);
  ASSERT_GE(first, 1);
  EXPECT_LT(first, 40);
  int tracked = 0;
  for (size_t k = first; k < s.results.size(); ++k) tracked += s.results[k].pose.has_value();
  EXPECT_EQ(tracked, static_cast<int>(s.results.size()) - first);
  const SegmentErrors e = Evaluate(s, 0);
  Report("fisheye 186 deg", s, e);
  EXPECT_LE(e.max_relative_rotation_deg, 0.1);
  EXPECT_LE(e.aligned_rms, 0.01 * e.path_length);
}

TEST(MonocularVo, PureRotationNeverInventsTranslation) {
  const auto camera = PinholeWithFov(752, 480, 60.0);
  const Sequence s = RunSequence(
      camera, 60,
      [](int k) {
        Pose rotated;  // ~0.35 deg per frame about a tilted axis, relative to the room's centre
        rotated.q = AxisAngle(Eigen::Vector3d(0.2, 1.0, 0.1), 0.006 * k);
        rotated.C = Eigen::Vector3d(0.3, -0.2, 0.1);
        return support::RoomCentre() * rotated;
      },
      NoBlank);
  for (const VoResult& r : s.results) {
    EXPECT_NE(r.state, VoState::kTracking) << r.message;
    EXPECT_FALSE(r.pose.has_value());
  }
}

TEST(MonocularVo, StaticCameraStaysInitialising) {
  const auto camera = PinholeWithFov(752, 480, 60.0);
  const Sequence s = RunSequence(
      camera, 30, [](int) { return RoomPose(10); }, NoBlank);
  for (const VoResult& r : s.results) {
    EXPECT_EQ(r.state, VoState::kInitialising) << r.message;
    EXPECT_FALSE(r.pose.has_value());
  }
}

// Blank frames lose the tracks; the first frame after them relocalises against the map and the
// segment goes on (a new segment only after VoOptions::relocalisation_timeout_s: see
// vo/relocalisation).
TEST(MonocularVo, BlankFramesLoseTrackingAndRelocaliseInTheSameSegment) {
  const auto camera = PinholeWithFov(752, 480, 60.0);
  const int blank_from = 60;
  const int blank_to = 63;  // frames 60, 61, 62 are blank
  const Sequence s =
      RunSequence(camera, 140, RoomPose, [&](int k) { return k >= blank_from && k < blank_to; });
  ASSERT_EQ(s.results[blank_from - 1].state, VoState::kTracking);
  for (int k = blank_from; k < blank_to; ++k) {
    EXPECT_EQ(s.results[k].state, VoState::kLost);
    EXPECT_FALSE(s.results[k].pose.has_value());
  }
  const VoResult& back = s.results[blank_to];
  ASSERT_TRUE(back.pose.has_value()) << back.message;
  EXPECT_TRUE(back.relocalised);
  EXPECT_EQ(back.relocalisations, 1);
  EXPECT_EQ(back.pose->segment, 0);
  EXPECT_FALSE(back.segment_start.has_value());
  for (int k = blank_to; k < static_cast<int>(s.results.size()); ++k) {
    ASSERT_TRUE(s.results[k].pose.has_value()) << "frame " << k << ": " << s.results[k].message;
    EXPECT_EQ(s.results[k].pose->segment, 0);
  }
  const SegmentErrors e = Evaluate(s, 0);
  Report("across the blank frames", s, e);
  EXPECT_LE(e.max_relative_rotation_deg, 0.1);
  EXPECT_LE(e.aligned_rms, 0.01 * e.path_length);
}

TEST(MonocularVo, BadImagesAreRejectedWithoutCrashing) {
  const auto camera = PinholeWithFov(320, 240, 60.0);
  MonocularVo vo(camera, 3);
  VoResult r = vo.Process(0, cv::Mat());
  EXPECT_FALSE(r.pose.has_value());
  EXPECT_NE(r.message.find("empty"), std::string::npos);
  r = vo.Process(1, cv::Mat(100, 100, CV_8UC1, cv::Scalar(0)));
  EXPECT_NE(r.message.find("100x100"), std::string::npos);
  r = vo.Process(2, cv::Mat(240, 320, CV_32FC1, cv::Scalar(0)));
  EXPECT_NE(r.message.find("unsupported"), std::string::npos);
  r = vo.Process(3, cv::Mat(240, 320, CV_8UC3, cv::Scalar(10, 20, 30)));  // converted, blank
  EXPECT_EQ(r.state, VoState::kInitialising);
  EXPECT_EQ(vo.frames_processed(), 4);
  MonocularVo no_camera(nullptr, 0);
  EXPECT_FALSE(no_camera.Process(0, cv::Mat(240, 320, CV_8UC1)).pose.has_value());
}

// The feature budget follows the field of view: a normal lens keeps max_features, a 186-degree
// fisheye (2 pi (1 - cos 93 deg) = 6.61 sr) tracks max_features * 6.61 / normal_fov_sr.
TEST(MonocularVo, FeatureBudgetFollowsTheFieldOfView) {
  const auto pinhole = PinholeWithFov(752, 480, 60.0);
  const auto fisheye = EquidistantWithFov(640, 640, 186.0);
  VoOptions options;
  const MonocularVo normal(pinhole, 0, options);
  const MonocularVo wide(fisheye, 1, options);
  // 60 x 40.5 degrees: 4 asin(sin 30 sin 20.2) = 0.69 sr.
  EXPECT_NEAR(normal.field_of_view_sr(), 0.69, 0.03);
  EXPECT_EQ(normal.feature_budget(), options.max_features);
  const double fisheye_sr = 2.0 * M_PI * (1.0 - std::cos(93.0 * M_PI / 180.0));
  EXPECT_NEAR(wide.field_of_view_sr(), fisheye_sr, 0.03 * fisheye_sr);
  EXPECT_NEAR(wide.feature_budget(), options.max_features * fisheye_sr / options.normal_fov_sr,
              0.03 * options.max_features * fisheye_sr / options.normal_fov_sr);
  options.normal_fov_sr = 0.0;  // off: max_features for every lens
  EXPECT_EQ(MonocularVo(fisheye, 1, options).feature_budget(), options.max_features);
  options.normal_fov_sr = -1.0;
  const std::string error = options.Check().message();
  EXPECT_FALSE(options.Check().ok());
  EXPECT_NE(error.find("normal_fov_sr"), std::string::npos);
}

TEST(VoOptions, CheckNamesTheField) {
  VoOptions options;
  EXPECT_TRUE(options.Check().ok()) << options.Check().message();
  EXPECT_TRUE(options.Check().message().empty());
  options.klt_window_px = 20;
  options.ransac_confidence = 1.5;
  // The first violated constraint, in the order of the fields.
  std::string error = options.Check().message();
  EXPECT_FALSE(options.Check().ok());
  EXPECT_EQ(error, "klt_window_px: must be odd and >= 5");
  options.klt_window_px = 21;
  error = options.Check().message();
  EXPECT_FALSE(options.Check().ok());
  EXPECT_EQ(error.rfind("ransac_confidence: ", 0), 0u) << error;
  EXPECT_EQ(ToString(VoState::kLost), "lost");
}

// Invalid options are rejected, not replaced by the defaults: the constructor throws
// InvalidOptions naming the options type and the field.
TEST(VoOptions, InvalidOptionsAreRejectedByTheConstructor) {
  camera::CameraSpec spec;
  spec.width = 752;
  spec.height = 480;
  spec.intrinsics = {450.0, 450.0, 375.5, 239.5};
  const std::shared_ptr<const camera::CameraModel> pinhole = camera::MakeCameraModel(spec).value();
  VoOptions options;
  options.max_features = 5;
  try {
    const MonocularVo vo(pinhole, 0, options);
    ADD_FAILURE() << "MonocularVo accepted max_features = 5";
  } catch (const InvalidOptions& e) {
    EXPECT_EQ(std::string(e.what()), "VoOptions: max_features: must be >= 20");
  }
  options = VoOptions{};
  options.ba_window = 2;
  EXPECT_THROW(MonocularVo(pinhole, 0, options), InvalidOptions);
  EXPECT_NO_THROW(MonocularVo(pinhole, 0, VoOptions{}));
}

}  // namespace
}  // namespace rigcal::vo
