// SPDX-License-Identifier: Apache-2.0
// WriteGroundTruth: a simulated rig's truth files, written atomically by the trajectory and rig
// YAML writers.
#include "rigcal/io/ground_truth_files.h"

#include <filesystem>
#include <utility>
#include <vector>

#include "rigcal/io/atomic_file.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;

// The comment at the top of a camera's trajectory file; `frame` names its reference frame.
std::string TruthTrajectoryComment(const std::string& camera, const std::string& frame) {
  return "simulated ground truth of camera " + camera +
         " (TUM: t tx ty tz qx qy qz qw; world_from_camera, metres)\nframe: " + frame;
}

TimedTrajectory Trajectory(const sim::SimulatedCameraTruth& camera,
                           const std::vector<Pose>& poses) {
  TimedTrajectory trajectory;
  trajectory.name = camera.name;
  trajectory.t_ns = camera.t_ns;
  trajectory.poses = poses;
  return trajectory;
}

// truth.yaml: the master's name and every slave's mounting, in rig order.
Status WriteTrueRig(const sim::SimulatedGroundTruth& truth, const fs::path& path) {
  if (truth.cameras.empty()) return Status::Ok();
  std::vector<std::pair<std::string, Similarity>> slaves;
  for (size_t i = 1; i < truth.cameras.size(); ++i) {
    slaves.emplace_back(truth.cameras[i].name, truth.cameras[i].master_from_camera);
  }
  return WriteFileAtomically(
      path.string(),
      RigToYaml(slaves, truth.cameras.front().name,
                "True rig of a simulated source: every slave's orientation and centre in the "
                "master\nframe (metres); scale 1 because the simulated truth is metric."));
}

}  // namespace

Status WriteGroundTruth(const sim::SimulatedGroundTruth& truth, const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Error{dir + ": cannot create directory: " + ec.message()};
  for (const sim::SimulatedCameraTruth& camera : truth.cameras) {
    if (Status status =
            WriteTrajectoryTum((fs::path(dir) / (camera.name + ".txt")).string(),
                               Trajectory(camera, camera.origin_from_camera),
                               TruthTrajectoryComment(camera.name, "the camera's pose at frame 0"));
        !status.ok()) {
      return status;
    }
    if (Status status =
            WriteTrajectoryTum((fs::path(dir) / ("world_" + camera.name + ".txt")).string(),
                               Trajectory(camera, camera.world_from_camera),
                               TruthTrajectoryComment(camera.name, "the simulated world (z up)"));
        !status.ok()) {
      return status;
    }
  }
  return WriteTrueRig(truth, fs::path(dir) / "truth.yaml");
}

}  // namespace rigcal::io
