// SPDX-License-Identifier: Apache-2.0
// CalibNode's end of a live capture (calib_node.h): what happened to the devices and the
// trigger, the recorded VO poses, and a simulated source's truth and errors.
#include <filesystem>
#include <sstream>

#include "calib_node_impl.h"
#include "rigcal/io/ground_truth_files.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::pipeline {
namespace {

// Every recorded VO pose of every camera to <dir>/<name>.txt in the rigcal native format
// (`t_ns qw qx qy qz Cx Cy Cz segment`), which `rigcal solve` reads.
Status WriteRecordedPoses(const std::string& dir, const std::vector<std::string>& names,
                          const Pipeline& pipeline) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return Error{"cannot create '" + dir + "': " + ec.message()};
  for (size_t i = 0; i < names.size(); ++i) {
    TimedTrajectory trajectory;
    trajectory.name = names[i];
    for (const CameraPose& p : pipeline.RecordedPoses(static_cast<int>(i))) {
      // A segment's reference pose and its first pose are distinct stamps; keep stamps
      // strictly increasing (a reader rejects anything else).
      if (!trajectory.t_ns.empty() && p.t_ns <= trajectory.t_ns.back()) continue;
      trajectory.t_ns.push_back(p.t_ns);
      trajectory.poses.push_back(p.pose);
      trajectory.segment.push_back(p.segment);
    }
    const std::string path = (std::filesystem::path(dir) / (names[i] + ".txt")).string();
    if (Status status = io::WriteTrajectoryNative(path, trajectory); !status.ok()) return status;
  }
  return Status::Ok();
}

// The end-of-run lines of the cameras, the folders, the V4L2 devices and the trigger.
std::vector<std::string> CaptureReport(const std::vector<CameraHealth>& cameras,
                                       const CaptureSources& sources) {
  std::ostringstream text;
  for (const CameraHealth& h : cameras) {
    if (h.dead) text << "camera '" << h.name << "' died: " << h.dead_reason << "\n";
    if (h.dropped_backlog > 0) {
      text << "camera '" << h.name << "': " << h.dropped_backlog
           << " frames dropped because its VO fell behind\n";
    }
  }
  ReportFolderProblems(sources.folders, "", text);
  ReportCaptureStats(sources.v4l2, "", text);
  ReportTrigger(sources, "", text);
  std::vector<std::string> lines;
  std::istringstream in(text.str());
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

}  // namespace

void CalibNode::Impl::FinishCapture() {
  if (recorder) {
    // After the last estimate went in (Finish).
    const Status stopped = recorder->Stop();
    summary.recording = recorder->Stats();
    if (!stopped.ok()) summary.recording_error = stopped.message();
  }
  if (pipeline) summary.camera_health = pipeline->Snapshot().cameras;
  summary.capture_report = CaptureReport(summary.camera_health, *sources);
  if (capture_loops) {
    for (const std::string& problem : capture_loops->Problems()) {
      summary.capture_report.push_back(problem);
    }
  }
  if (!pipeline) return;
  if (!options.poses_dir.empty()) {
    if (Status status = WriteRecordedPoses(options.poses_dir, names, *pipeline); !status.ok()) {
      summary.errors.push_back(status.message());
    }
  }
  const std::optional<sim::SimulatedRig>& rig = sources->rig;
  if (rig && !options.truth_dir.empty() && !options.poses_dir.empty()) {
    // In real time the devices' stamps start with the rig clock: rewrite the truth now that
    // it ran, so its stamps match the written poses (before the run they count from 0).
    if (Status status = io::WriteGroundTruth(rig->GroundTruth(), options.truth_dir); !status.ok()) {
      summary.errors.push_back(status.message());
    }
  }
  if (!rig || !options.evaluate) return;
  std::vector<std::vector<CameraPose>> poses;
  for (size_t i = 0; i < names.size(); ++i) {
    poses.push_back(pipeline->RecordedPoses(static_cast<int>(i)));
  }
  auto evaluation = EvaluateRun(*rig, poses, summary.estimate.rig);
  if (evaluation) {
    summary.evaluation = std::move(*evaluation);
  } else {
    log->warn("no evaluation: {}", evaluation.error());
  }
}

}  // namespace rigcal::pipeline
