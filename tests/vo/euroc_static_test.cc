// SPDX-License-Identifier: Apache-2.0
// MonocularVo on real images: the 95 static EuRoC V1_01 stereo frames in
// ../shared/data/euroc_v101_static (the MAV stands on the ground). With no motion the VO must
// not invent one: it stays initialising (an initialisation would set a unit baseline out of
// noise). cam1's index lists 4 images that do not exist: they are reported and skipped.

#include <gtest/gtest.h>

#include <filesystem>

#include "rigcal/camera/camera_spec.h"
#include "rigcal/capture/image_folder_device.h"
#include "rigcal/vo/monocular_vo.h"
#include "support/skip.h"

namespace rigcal::vo {
namespace {

const std::string kEuroc = std::string(RIGCAL_SHARED_DATA_DIR) + "/euroc_v101_static/mav0";

std::shared_ptr<const camera::CameraModel> EurocCamera(int index) {
  // mav0/cam<index>/sensor.yaml
  camera::CameraSpec spec;
  spec.name = "cam" + std::to_string(index);
  spec.model = camera::CameraSpec::Model::kPinhole;
  spec.width = 752;
  spec.height = 480;
  if (index == 0) {
    spec.intrinsics = {458.654, 457.296, 367.215, 248.375};
    spec.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05};
  } else {
    spec.intrinsics = {457.587, 456.134, 379.999, 255.238};
    spec.distortion = {-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05};
  }
  auto model = camera::MakeCameraModel(spec);
  EXPECT_TRUE(model.ok()) << model.error();
  if (!model.ok()) return nullptr;
  return std::shared_ptr<const camera::CameraModel>(std::move(*model));
}

struct StaticRun {
  int frames = 0;
  int poses = 0;
  int tracking = 0;
  int lost = 0;
  size_t skipped = 0;
  int min_tracks = 1 << 30;
};

StaticRun RunCamera(int index) {
  StaticRun run;
  auto device = capture::ImageFolderDevice::Open(kEuroc + "/cam" + std::to_string(index),
                                                 "cam" + std::to_string(index), index);
  EXPECT_TRUE(device.ok()) << device.error();
  const auto camera = EurocCamera(index);
  if (!device.ok() || camera == nullptr) return run;
  MonocularVo vo(camera, index);
  for (;;) {
    auto grabbed = (*device)->Grab();
    EXPECT_TRUE(grabbed.ok()) << grabbed.error();
    if (!grabbed.ok() || !grabbed->has_value()) break;
    const capture::Frame& frame = **grabbed;
    const VoResult r = vo.Process(frame.t_ns, frame.image);
    ++run.frames;
    run.poses += r.pose.has_value();
    run.tracking += r.state == VoState::kTracking;
    run.lost += r.state == VoState::kLost;
    if (run.frames > 1) run.min_tracks = std::min(run.min_tracks, r.tracked_features);
  }
  run.skipped = (*device)->skipped_count();
  return run;
}

TEST(EurocStatic, VoReportsNoMotionAndMissingImagesAreReported) {
  if (!std::filesystem::exists(kEuroc + "/cam0/data.csv")) RIGCAL_SKIP_MISSING() << "no " << kEuroc;
  for (int index : {0, 1}) {
    SCOPED_TRACE("cam" + std::to_string(index));
    const StaticRun run = RunCamera(index);
    EXPECT_EQ(run.frames, 95);
    EXPECT_EQ(run.poses, 0);
    EXPECT_EQ(run.tracking, 0);
    EXPECT_EQ(run.lost, 0);
    EXPECT_GE(run.min_tracks, 60);  // the real images are tracked, there is just no parallax
    EXPECT_EQ(run.skipped, index == 1 ? 4u : 0u);
  }
}

}  // namespace
}  // namespace rigcal::vo
