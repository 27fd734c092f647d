// SPDX-License-Identifier: Apache-2.0
// `rigcal vo`: the monocular VO of one camera of a rig config alone, every frame of its source in
// order (no pacing, no frame dropped), for checking the VO on a single (real) sequence: where it
// initialises, the share of frames with a pose, its scale segments and relocalisations, its time
// per frame, and optionally its poses in the native trajectory format.
#include <algorithm>
#include <iomanip>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/pipeline/capture_sources.h"
#include "rigcal/vo/monocular_vo.h"

namespace rigcal::cli {
namespace {

constexpr char kCommand[] = "vo";

struct VoArgs {
  std::string config;
  std::string camera;
  std::string poses_out;
  int64_t max_frames = 0;
};

struct VoSummary {
  int64_t frames = 0;
  int64_t first_pose_frame = -1;
  int64_t first_pose_t_ns = 0;
  int64_t first_frame_t_ns = 0;
  int64_t frames_with_pose = 0;
  int segments = 0;
  int relocalisations = 0;
  std::vector<double> processing_ms;
};

// A quantile by nearest rank (0 for no value).
double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * values.size()));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

void Record(int64_t t_ns, const vo::VoResult& r, VoSummary* summary, TimedTrajectory* poses) {
  if (summary->frames == 0) summary->first_frame_t_ns = t_ns;
  ++summary->frames;
  summary->processing_ms.push_back(r.processing_ms);
  summary->relocalisations = r.relocalisations;
  if (r.segment_start) ++summary->segments;
  if (!r.pose) return;
  if (summary->first_pose_frame < 0) {
    summary->first_pose_frame = summary->frames - 1;
    summary->first_pose_t_ns = r.pose->t_ns;
  }
  ++summary->frames_with_pose;
  if (!poses->t_ns.empty() && r.pose->t_ns <= poses->t_ns.back()) return;
  poses->t_ns.push_back(r.pose->t_ns);
  poses->poses.push_back(r.pose->pose);
  poses->segment.push_back(r.pose->segment);
}

void PrintSummary(const std::string& camera, const VoSummary& s) {
  std::cout << std::fixed << std::setprecision(2);
  std::cout << "rigcal vo: camera '" << camera << "': " << s.frames << " frames, ";
  if (s.first_pose_frame < 0) {
    std::cout << "no pose (the VO did not initialise)\n";
  } else {
    const int64_t after = s.frames - s.first_pose_frame;
    std::cout << "first pose at frame " << s.first_pose_frame << " ("
              << 1e-9 * static_cast<double>(s.first_pose_t_ns - s.first_frame_t_ns)
              << " s), a pose for " << s.frames_with_pose << " of the " << after
              << " frames from it ("
              << 100.0 * static_cast<double>(s.frames_with_pose) /
                     static_cast<double>(std::max<int64_t>(after, 1))
              << " %), " << s.segments << " scale segment(s), " << s.relocalisations
              << " relocalisation(s)\n";
  }
  std::cout << "rigcal vo: VO time per frame median " << Quantile(s.processing_ms, 0.5)
            << " ms, p90 " << Quantile(s.processing_ms, 0.9) << " ms\n";
}

int RunVo(const VoArgs& args) {
  auto config = io::LoadRigConfig(args.config);
  if (!config) return PrintCommandError(kCommand, config.error());
  const std::vector<std::string> names = config->CameraNames();
  const auto it = std::find(names.begin(), names.end(), args.camera);
  if (it == names.end()) {
    return PrintCommandError(kCommand, args.config + ": no camera '" + args.camera + "'");
  }
  const size_t index = static_cast<size_t>(it - names.begin());
  auto sources = pipeline::OpenCaptureSources(*config, true, "rigcal vo: ", std::cerr);
  if (!sources) return PrintCommandError(kCommand, sources.error());
  capture::CameraDevice& device = *sources->devices[index];
  vo::MonocularVo vo(sources->models[index], static_cast<int>(index));
  VoSummary summary;
  TimedTrajectory poses;
  poses.name = args.camera;
  while (args.max_frames == 0 || summary.frames < args.max_frames) {
    auto frame = device.Grab();
    if (!frame)
      return PrintCommandError(kCommand, "camera '" + args.camera + "': " + frame.error());
    if (!*frame) break;  // the end of the source
    Record((*frame)->t_ns, vo.Process((*frame)->t_ns, (*frame)->image), &summary, &poses);
  }
  PrintSummary(args.camera, summary);
  if (!args.poses_out.empty()) {
    const Status written = io::WriteTrajectoryNative(args.poses_out, poses);
    if (!written.ok()) return PrintCommandError(kCommand, written.message());
    std::cout << "rigcal vo: " << poses.size() << " poses written to " << args.poses_out << "\n";
  }
  return kExitOk;
}

}  // namespace

void RegisterVo(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<VoArgs>();
  CLI::App* cmd = app.add_subcommand(
      "vo",
      "The monocular VO of one camera of a rig config alone, over every frame of its source in\n"
      "order (image folders, or a simulated rig not paced): where it initialises, the share of\n"
      "frames with a pose, scale segments, relocalisations and the time per frame.");
  cmd->add_option("--config", args->config, "Rig config YAML with a `source:` section")->required();
  cmd->add_option("--camera", args->camera, "The camera's name in the config")->required();
  cmd->add_option("--poses-out", args->poses_out,
                  "Write the VO poses to this file (rigcal native format with the scale segment "
                  "column)");
  cmd->add_option("--max-frames", args->max_frames, "Stop after this many frames (0 = source end)")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([args, exit_code]() { *exit_code = RunVo(*args); });
}

}  // namespace rigcal::cli
