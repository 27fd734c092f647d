// SPDX-License-Identifier: Apache-2.0
// Reads the KITTI 00 ground truth (kitti.h).
#include "support/kitti.h"

#include <filesystem>

#include "rigcal/io/trajectory_io.h"

namespace rigcal::support {

Expected<SampledTrajectory> LoadKitti00() {
  const std::filesystem::path dir = std::filesystem::path(RIGCAL_SHARED_DATA_DIR) / "trajectories";
  const std::filesystem::path poses = dir / "KITTI_00_gt.txt";
  const std::filesystem::path times = dir / "KITTI_00_gt_times.txt";
  if (!std::filesystem::exists(poses) || !std::filesystem::exists(times)) {
    return Error{"KITTI 00 ground truth not found in " + dir.string()};
  }
  auto read = io::ReadKittiTrajectory(poses.string(), times.string());
  if (!read) return Error{read.error()};
  SampledTrajectory out;
  out.t_ns = read->t_ns;
  out.poses = read->poses;
  return out;
}

}  // namespace rigcal::support
