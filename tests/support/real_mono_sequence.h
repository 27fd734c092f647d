// SPDX-License-Identifier: Apache-2.0
#pragma once
// The real monocular sequences of ../shared/data/real_mono (README-provenance.txt there), for
// the VO's tests and evaluations: the frames read by capture's ImageFolderDevice as a plain
// folder (the recordings have no stamps; 30 Hz is assumed), the intrinsics of the sequence's
// calibration file, and for visp_rbt_sequence the metric AprilTag poses of every frame (the
// grid's, and each detected tag's own).
//
// Poses are Pose{q, C}: the camera's orientation world_from_cam and centre in the grid's (or a
// tag's) frame, i.e. the inverse of the files' camera-from-object cMo.

#include <Eigen/Core>
#include <array>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::support {

inline constexpr double kRealMonoRateHz = 30.0;

struct RealMonoSequence {
  std::string name;    // "visp_rbt_sequence" or "visp_mbt_cube"
  std::string folder;  // the images
  std::shared_ptr<const camera::CameraModel> camera;
  std::vector<int64_t> t_ns;  // frame k at k / 30 s
  std::vector<cv::Mat> grey;  // CV_8UC1 640x480
  // visp_rbt_sequence only (empty otherwise), per frame: the camera in the grid frame, and in
  // the frame of every tag detected in it (by tag id).
  std::vector<Pose> grid_from_cam;
  std::vector<std::map<int, Pose>> tag_from_cam;
  // The detected corners of every tag, pixels, in the order of tag_corners_in_tag.
  std::vector<std::map<int, std::array<Eigen::Vector2d, 4>>> tag_corners_px;
  double tag_size_m = 0.0;
  // The corners of a tag in its own frame (z = 0), metres.
  std::array<Eigen::Vector3d, 4> TagCornersInTag() const;
};

// How well the grid pose of each frame explains its tags' corners: the RMS distance, pixels,
// between the detected corners and their projection at the grid pose, the tags placed on the
// grid where all frames together put them (each tag's pose in the grid frame, averaged over
// the frames). Blurred frames, whose detections and poses are worse, stand out.
std::vector<double> TagGridResidualsPx(const RealMonoSequence& sequence);

// The folder of sequence `name` under RIGCAL_SHARED_DATA_DIR.
std::string RealMonoFolder(const std::string& name);
// Whether the sequence's images are there (tests skip with RIGCAL_SKIP_MISSING otherwise).
bool RealMonoAvailable(const std::string& name);
// Reads every frame, the intrinsics and (visp_rbt_sequence) the tag poses.
Expected<RealMonoSequence> LoadRealMono(const std::string& name);

// Pose of a camera from the 4x4 row-major camera-from-object matrix cMo: the object frame is
// the world.
Pose PoseFromCameraFromObject(const Eigen::Matrix4d& cam_from_object);

}  // namespace rigcal::support
