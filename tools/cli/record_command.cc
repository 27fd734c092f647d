// SPDX-License-Identifier: Apache-2.0
// `rigcal record`: captures every camera of the configured source into an LCM log
// (RIGCAL_IMAGE_<camera>; with VO also RIGCAL_POSE_<camera> and RIGCAL_EXTRINSICS), through the
// same CalibNode capture as `rigcal run` (calib_node.h), with a progress line.
#include <cmath>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "exit_codes.h"
#include "record_progress.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/pipeline/calib_node.h"
#include "stop_signal.h"

namespace rigcal::cli {
namespace {

constexpr char kPrefix[] = "rigcal record: ";

struct RecordArgs {
  std::string config;
  pipeline::CalibNodeOptions node;
  std::string image_encoding = "raw";
  double split_mb = 0.0;
  bool force = false;  // accepted, no effect: logs are always replaced (output_files.h)
};

int RunRecord(const RecordArgs& args) {
  auto config = io::LoadRigConfig(args.config);
  if (!config) {
    std::cerr << kPrefix << config.error() << "\n";
    return kExitError;
  }
  const size_t cameras = config->cameras.size();
  pipeline::CalibNodeOptions options = args.node;
  options.recorder.image.encoding = *pipeline::ParseImageEncoding(args.image_encoding);
  options.recorder.log.split_bytes = static_cast<int64_t>(std::llround(args.split_mb * 1e6));
  RecordProgress progress;
  options.on_recording = [&progress](const pipeline::RecorderStats& s) { progress.Update(s); };
  pipeline::CalibNode node(std::move(*config), options);
  if (const Status status = node.Open(); !status.ok()) {
    std::cerr << kPrefix << status.message() << "\n";
    return kExitError;
  }
  std::cerr << kPrefix << "recording " << cameras << " cameras ("
            << ToString(options.recorder.image.encoding)
            << (options.record_no_vo ? "" : ", with VO poses") << ") to " << options.record_path
            << "; Ctrl-C stops cleanly\n";
  StopSignal stop_signal;
  const double cpu_start_s = lcm::ProcessCpuSeconds();
  const pipeline::CalibNodeSummary summary = node.Run(stop_signal.flag());
  const double elapsed_s = progress.elapsed_s();
  if (summary.recording) progress.Update(*summary.recording, /*force=*/true);
  progress.End();
  for (const std::string& line : summary.capture_report) std::cerr << kPrefix << line << "\n";
  for (const std::string& error : summary.errors) std::cerr << kPrefix << error << "\n";
  if (!summary.recording_error.empty() || !summary.recording) {
    std::cerr << kPrefix << summary.recording_error << "\n";
    return kExitError;
  }
  PrintRecordingSummary(*summary.recording, elapsed_s,
                        100.0 * (lcm::ProcessCpuSeconds() - cpu_start_s) / elapsed_s);
  return summary.errors.empty() ? kExitOk : kExitError;
}

void AddRecordOptions(CLI::App* cmd, RecordArgs* args) {
  pipeline::CalibNodeOptions& node = args->node;
  // A missing config is bad input (exit 1, named by the loader), not a usage error.
  cmd->add_option("--config", args->config, "Rig config YAML with a `source:` section")->required();
  cmd->add_option("-o,--out", node.record_path, "LCM log file to write")->required();
  cmd->add_option("--duration", node.duration_s, "Stop after this many seconds (0 = source end)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--image-encoding", args->image_encoding,
                  "raw (no CPU, 1 byte per pixel), png (lossless, smaller, CPU-heavy) or jpeg "
                  "(lossy, smallest)")
      ->check(CLI::IsMember({"raw", "png", "jpeg"}))
      ->capture_default_str();
  cmd->add_option("--jpeg-quality", node.recorder.image.jpeg_quality, "JPEG quality, 1..100")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--split-mb", args->split_mb,
                  "Start a new file before one would exceed this many MB (10^6 bytes); the files "
                  "are then named as lcm-logger -i names them: OUT.00, OUT.01, ... (0 = one file)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-vo", node.record_no_vo,
                "Record the images only (no VO, poses or extrinsics)");
  cmd->add_flag("--fast", node.fast,
                "Do not pace a simulated source in real time: record as fast as possible, "
                "without dropping frames");
  // Existing log files are replaced (output_files.h), each with the new log's first event.
  node.recorder.log.overwrite = true;
  cmd->add_flag("-f,--force", args->force,
                "Accepted for older scripts: existing log files are always replaced (below)");
}

}  // namespace

void RegisterRecord(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<RecordArgs>();
  args->node.capture = true;
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Record every camera of the configured source into an LCM log (lcm-logger format, plays in\n"
      "lcm-logplayer): RIGCAL_IMAGE_<camera> image_t per frame and, unless --no-vo, the VO poses\n"
      "(RIGCAL_POSE_<camera>) and the rig estimate (RIGCAL_EXTRINSICS, at the config's\n"
      "publish.extrinsics_rate_hz) of the live pipeline. A progress line (MB, frames per\n"
      "camera, drops) refreshes in place on a terminal, one line per second otherwise. Every\n"
      "event is written whole and the log synced every second: after a crash or power loss it\n"
      "is readable up to its last complete event.");
  AddRecordOptions(cmd, args.get());
  cmd->footer(
      "Exit status: 0 recorded; 1 bad config, the log cannot be written (the message names the "
      "file), 2 usage.");
  cmd->callback([args, exit_code]() { *exit_code = RunRecord(*args); });
}

}  // namespace rigcal::cli
