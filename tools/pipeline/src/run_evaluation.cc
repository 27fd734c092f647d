// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/run_evaluation.h"

namespace rigcal::pipeline {

io::TrueTrajectory SimulatedTrajectory(const sim::SimulatedRig& rig, int camera) {
  const double epoch_ns = static_cast<double>(rig.epoch_ns());
  return [&rig, camera, epoch_ns](int64_t t_ns) -> std::optional<Pose> {
    return rig.WorldFromCameraAt(camera, 1e-9 * (static_cast<double>(t_ns) - epoch_ns));
  };
}

Expected<RunEvaluation> EvaluateRun(const sim::SimulatedRig& rig,
                                    const std::vector<std::vector<CameraPose>>& poses,
                                    const RigCalibration& result) {
  if (poses.size() != static_cast<size_t>(rig.num_cameras())) {
    return Error{"evaluation: expected poses of " + std::to_string(rig.num_cameras()) +
                 " cameras, got " + std::to_string(poses.size())};
  }
  io::TruthInput input;
  input.unit = io::TruthUnit::kMetric;
  input.poses = poses;
  for (int camera = 0; camera < rig.num_cameras(); ++camera) {
    input.trajectories.push_back(SimulatedTrajectory(rig, camera));
  }
  const std::vector<Similarity> truth = rig.TrueRig();
  for (size_t i = 0; i < result.slaves.size() && i < truth.size(); ++i) {
    input.mountings[result.slaves[i].name] = truth[i];
  }
  return io::CompareWithTruth(result, input);
}

}  // namespace rigcal::pipeline
