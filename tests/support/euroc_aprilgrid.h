// SPDX-License-Identifier: Apache-2.0
#pragma once
// Real rig data for tests: the EuRoC "imu_april" calibration sequence as AprilGrid corner
// detections (no images), turned into per-camera poses with OpenCV PnP.
//
// Data: <RIGCAL_SHARED_DATA_DIR>/euroc_calib_aprilgrid/imu_april/ (see README-provenance.txt
// one level up): config.yaml (intrinsics pinhole + radtan4, ground truth T_cam0_cam1) and
// cam0/, cam1/ with one CSV per frame, named <t_ns>.csv, columns
//   #ts,tag_rows,tag_cols,tag_size,tag_spacing,kp_x,kp_y,p_x,p_y,p_z,tag_id,corner_idx
// (kp = distorted pixel coordinates, p = corner in the target frame, metres).
//
// Frames: PnP gives each camera's pose in the target frame, target_from_cam (q world_from_cam
// with world = target, C = camera centre in the target frame). Both cameras see the same
// target, so these poses are "individual reference poses" of the thesis (4.2); the calibrator
// only uses relative motions, for which any fixed reference frame per camera is as good as the
// camera's first pose.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"

namespace rigcal::support {

// Pinhole camera with radial-tangential (radtan4 = OpenCV k1, k2, p1, p2) distortion.
struct PinholeRadtan {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  std::array<double, 4> dist = {0.0, 0.0, 0.0, 0.0};  // k1, k2, p1, p2
};

// config.yaml of the sequence.
struct EurocAprilGridConfig {
  PinholeRadtan cam0;
  PinholeRadtan cam1;
  // Ground truth T_cam0_cam1: maps cam1 points to cam0 (master_from_slave), scale 1.
  Similarity cam0_from_cam1;
};

// Corner detections of one frame of one camera.
struct AprilGridFrame {
  int64_t t_ns = 0;
  std::vector<Eigen::Vector2d> pixels;         // distorted pixel coordinates
  std::vector<Eigen::Vector3d> target_points;  // same corners in the target frame [m]
};

struct PnpOptions {
  int min_corners = 12;             // frames with fewer corners are rejected
  double max_mean_reproj_px = 2.0;  // frames with a larger mean reprojection error are rejected
};

// One accepted PnP pose.
struct TargetPose {
  int64_t t_ns = 0;
  Pose target_from_cam;  // q: target_from_cam rotation, C: camera centre in target
  double mean_reproj_px = 0.0;
  int corners = 0;
};

struct PnpStats {
  int frames = 0;           // CSV files read
  int too_few_corners = 0;  // includes frames without detections
  int pnp_failed = 0;
  int high_reprojection = 0;
  int accepted = 0;
  double median_reproj_px = 0.0;  // over accepted frames
};

// <RIGCAL_SHARED_DATA_DIR>/euroc_calib_aprilgrid/imu_april
std::string EurocAprilGridDir();
// True when the sequence is present; otherwise *reason says what is missing (for GTEST_SKIP).
bool EurocAprilGridAvailable(std::string* reason);

Expected<EurocAprilGridConfig> LoadEurocAprilGridConfig(const std::string& dir);
// Every <t_ns>.csv of `camera_dir`, sorted by time. Frames without detections are kept (empty).
Expected<std::vector<AprilGridFrame>> LoadAprilGridFrames(const std::string& camera_dir);

// PnP per frame (IPPE for the planar target, then Levenberg-Marquardt refinement, distortion
// handled by passing the radtan coefficients to OpenCV). Frames failing `options` are dropped
// and counted in *stats (may be null).
std::vector<TargetPose> EstimateTargetPoses(const std::vector<AprilGridFrame>& frames,
                                            const PinholeRadtan& camera, const PnpOptions& options,
                                            PnpStats* stats);

struct EurocRig {
  RigRecording recording;  // master "cam0", one slave "cam1", segment 0 everywhere
  Similarity truth;        // cam0_from_cam1 (scale 1 until a slave's positions are scaled)
  PnpStats cam0_stats;
  PnpStats cam1_stats;
};

// Loads the sequence, runs PnP in both cameras and keeps the stamps where both have a pose.
Expected<EurocRig> LoadEurocAprilGridRig(const PnpOptions& options = {});

// Multiplies every camera centre of `track` by `factor` (simulates an odometry of another
// unit). The similarity that maps this track to the master then has its scale divided by
// `factor`.
void ScalePositions(CameraTrack* track, double factor);

// Writes one track as a TUM trajectory: "t tx ty tz qx qy qz qw" per line, t in seconds with 9
// decimals (exact from t_ns), position = camera centre C, rotation = q (world_from_cam).
// Returns false and sets *error (may be null) when the file cannot be written.
bool WriteTumTrajectory(const std::string& path, const std::vector<int64_t>& t_ns,
                        const CameraTrack& track, std::string* error);

// Writes the truth file read by `rigcal solve --truth`:
//   <slave_name>: {q_wxyz: [w, x, y, z], C: [x, y, z], scale: s}
bool WriteTruthYaml(const std::string& path, const std::string& slave_name,
                    const Similarity& master_from_slave, std::string* error);

}  // namespace rigcal::support
