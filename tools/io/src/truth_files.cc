// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/truth_files.h"

#include <filesystem>

#include "rigcal/io/rig_files.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::io {
namespace {

std::vector<CameraPose> CameraPoses(const TimedTrajectory& trajectory, int camera) {
  std::vector<CameraPose> poses;
  for (size_t k = 0; k < trajectory.size(); ++k) {
    CameraPose p;
    p.camera = camera;
    p.t_ns = trajectory.t_ns[k];
    p.pose = trajectory.poses[k];
    p.segment = k < trajectory.segment.size() ? trajectory.segment[k] : 0;
    poses.push_back(p);
  }
  return poses;
}

}  // namespace

Expected<TruthFiles> ReadTruthFiles(const std::string& path,
                                    const std::vector<std::string>& cameras) {
  TruthFiles files;
  std::error_code ec;
  const bool directory = std::filesystem::is_directory(path, ec);
  const std::string rig = directory ? (std::filesystem::path(path) / "truth.yaml").string() : path;
  // The first camera is the master: a truth naming another one is an error (rig_files.h).
  auto mountings = ReadTrueMountings(rig, cameras.empty() ? "" : cameras.front());
  if (!mountings) return Error{mountings.error()};
  files.mountings = std::move(*mountings);
  if (!directory) return files;
  for (const std::string& camera : cameras) {
    const std::string file = (std::filesystem::path(path) / (camera + ".txt")).string();
    if (!std::filesystem::exists(file, ec)) {
      return Error{path + ": no true trajectory " + camera + ".txt for camera '" + camera + "'"};
    }
    auto trajectory = ReadTrajectory(file);
    if (!trajectory) return Error{trajectory.error()};
    files.trajectories[camera] = SampledTrajectory(std::move(*trajectory));
  }
  return files;
}

Expected<TruthComparison> CompareRunWithTruth(const RigCalibration& result, const TruthFiles& truth,
                                              TruthUnit unit,
                                              const std::vector<TimedTrajectory>& odometry) {
  TruthInput input;
  input.mountings = truth.mountings;
  input.unit = unit;
  if (!truth.trajectories.empty()) {
    for (size_t i = 0; i < odometry.size(); ++i) {
      const auto it = truth.trajectories.find(odometry[i].name);
      input.poses.push_back(CameraPoses(odometry[i], static_cast<int>(i)));
      input.trajectories.push_back(it == truth.trajectories.end() ? TrueTrajectory{} : it->second);
    }
  }
  return CompareWithTruth(result, input);
}

}  // namespace rigcal::io
