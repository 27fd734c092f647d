// SPDX-License-Identifier: Apache-2.0
#pragma once
// OpenCV's hand-eye calibration (cv::calibrateHandEye, AX = XB) as a peer of the rig
// calibrator in tests and benchmarks.
//
// Mapping of the rig onto OpenCV's hand-eye problem. Camera poses are camera-local absolute
// poses: M_k = ref0_from_master_k (master), S_k = ref1_from_slave_k (slave). The rig constant is
// ref0_from_ref1 = M_k X S_k^-1 for every k, with X = master_from_slave. OpenCV's constant is
// base_from_target = gripper2base_k * cam2gripper * target2cam_k. Hence
//   gripper2base_k = M_k          (gripper = master camera, base = master reference frame)
//   target2cam_k   = S_k^-1       (cam = slave camera, target = slave reference frame)
//   cam2gripper    = X = master_from_slave (rotation q, translation C of the Similarity).
// OpenCV forms motions from all pairs (i, j), i < j, of the K poses: O(K^2) time and memory.
// OpenCV assumes one metric for both cameras: it has no scale, the returned Similarity has
// scale 1.

#include <string>
#include <vector>

#include "rigcal/base/types.h"

namespace rigcal::support {

enum class HandEyeMethod { kTsai, kPark, kHoraud, kAndreff, kDaniilidis };

inline constexpr HandEyeMethod kAllHandEyeMethods[] = {
    HandEyeMethod::kTsai, HandEyeMethod::kPark, HandEyeMethod::kHoraud, HandEyeMethod::kAndreff,
    HandEyeMethod::kDaniilidis};

std::string ToString(HandEyeMethod method);

struct HandEyeResult {
  HandEyeMethod method = HandEyeMethod::kTsai;
  bool ok = false;               // false when OpenCV threw or returned a non-finite result
  std::string error;             // OpenCV's message when !ok
  Similarity master_from_slave;  // scale always 1
};

// Runs one OpenCV method on time-corresponding absolute poses of master and slave (equal
// sizes, at least 3). Never throws.
HandEyeResult OpenCvHandEye(const std::vector<Pose>& master_poses,
                            const std::vector<Pose>& slave_poses, HandEyeMethod method);

// All five methods on the same poses.
std::vector<HandEyeResult> OpenCvHandEyeAll(const std::vector<Pose>& master_poses,
                                            const std::vector<Pose>& slave_poses);

// Every `stride`-th pose of the master and slave `slave_index` of `recording`, for OpenCV's
// O(K^2) pair construction on long recordings.
void SubsampledPoses(const RigRecording& recording, int slave_index, int stride,
                     std::vector<Pose>* master_poses, std::vector<Pose>* slave_poses);

}  // namespace rigcal::support
