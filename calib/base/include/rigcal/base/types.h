// SPDX-License-Identifier: Apache-2.0
#pragma once
// Value types shared by every layer: poses, trajectories, rig parameters.
// Notation follows the thesis (chapter 4): camera i's pose at time k is
// T_i^k = [R_i^k | C_i^k] (rotation world_from_cam and camera centre in its reference frame).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal {

// A rigid pose: orientation world_from_cam and camera centre C in the world (reference) frame.
// Maps a point in camera coordinates to world coordinates as p_world = R p_cam + C.
struct Pose {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();

  Eigen::Matrix3d R() const { return q.toRotationMatrix(); }
  // Pose of `other` expressed in this pose's frame: this^-1 * other.
  Pose Between(const Pose& other) const;
  Pose Inverse() const;
  Pose operator*(const Pose& other) const;
};

// The similarity dT_i = [dλ dR | dC] of a slave camera: its orientation and centre in the
// master frame, and the factor that maps slave odometry units to master units.
// p_master = scale * R(q) * p_slave + C.
struct Similarity {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d C = Eigen::Vector3d::Zero();
  double scale = 1.0;
};

// One camera's pose from its odometry, as it travels from a VO thread (or an LCM channel) to
// the estimator. `pose` is camera-local (the camera's own reference frame and unit).
struct CameraPose {
  int camera = 0;            // index in the rig: 0 = master, 1..N = slaves
  int64_t t_ns = 0;          // capture time, CLOCK_MONOTONIC of the capturing host
  int64_t trigger_seq = -1;  // hardware trigger pulse number, -1 when unknown
  int segment = 0;           // odometry scale segment (a VO re-initialisation opens a new one)
  Pose pose;
  double quality = 1.0;  // tracking quality in [0, 1]: 1 as well tracked as the camera usually is
};

// Time-corresponding poses of the master and every slave camera: entry k of every vector
// belongs to stamp t_ns[k]. `segment` is the camera's scale segment id at that pose (a VO
// re-initialisation opens a new one); poses of one segment share one odometry scale.
struct CameraTrack {
  std::string name;
  std::vector<Pose> poses;
  std::vector<int> segment;

  // The segment of pose k (0 when the track has no segment ids).
  int SegmentAt(size_t k) const { return segment.empty() ? 0 : segment[k]; }
};

struct RigRecording {
  std::vector<int64_t> t_ns;
  CameraTrack master;
  std::vector<CameraTrack> slaves;

  size_t size() const { return t_ns.size(); }
  // Pose k of camera `camera` (0 = master, i + 1 = slave i) as odometry delivers it.
  CameraPose PoseAt(int camera, size_t k) const;
  // Every camera's pose k, the set the online estimator takes (RigEstimator::AddSet).
  std::vector<std::optional<CameraPose>> SetAt(size_t k) const;
  // Success when consistent (one pose and at most one segment id per stamp, stamps
  // increasing), else an error naming the camera whose sizes disagree or the first stamp out
  // of order.
  Status Check() const;
};

// One rig motion between two times a -> b, seen by the master and by one slave:
// T_0^{a->b} and T_i^{a->b}, each expressed in the camera's own frame at time a.
struct RigMotion {
  Pose master;
  Pose slave;
  int segment = 0;  // slave scale segment of both ends
  int64_t t_a_ns = 0;
  int64_t t_b_ns = 0;
};

}  // namespace rigcal
