// `rigcal record`: captures every camera of the configured source into an LCM log
// (RIGCAL_IMAGE_<camera>; with VO also RIGCAL_POSE_<camera> and RIGCAL_EXTRINSICS), with a
// progress line.
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "commands.h"
#include "exit_codes.h"
#include "progress_line.h"
#include "rigcal/base/logging.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/lcm/shared_bus.h"
#include "rigcal/pipeline/calib_node.h"
#include "rigcal/pipeline/capture_loops.h"
#include "rigcal/pipeline/capture_sources.h"
#include "rigcal/pipeline/log_recorder.h"
#include "rigcal/pipeline/pipeline.h"
#include "stop_signal.h"

namespace rigcal::cli {
namespace {

using Clock = std::chrono::steady_clock;

constexpr char kPrefix[] = "rigcal record: ";

struct RecordArgs {
  std::string config;
  std::string out;
  double duration_s = 0.0;
  std::string image_encoding = "raw";
  int jpeg_quality = 90;
  double split_mb = 0.0;
  bool no_vo = false;
  bool fast = false;
  bool force = false;
};

// The poses the pipeline publishes on its in-process bus, recorded as they come.
struct PoseTap {
  pipeline::LogRecorder* recorder = nullptr;
  lcm::MessageValidator validator;
};

void OnPose(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, PoseTap* tap) {
  // The message's utime (capture time) dates the event; an invalid message is not recorded.
  auto msg = tap->validator.Decode<camera_pose_t>(channel, rbuf->data, rbuf->data_size);
  if (!msg) return;
  const auto* begin = static_cast<const uint8_t*>(rbuf->data);
  tap->recorder->Record(channel, msg->utime, std::vector<uint8_t>(begin, begin + rbuf->data_size));
}

// "  12.0 s | 86.4 MB (7.2 MB/s) | frames 240 240 | drops 0 | 1 file".
std::string ProgressText(double elapsed_s, const pipeline::RecorderStats& s) {
  char buf[256];
  const double mb = static_cast<double>(s.bytes) / 1e6;
  std::snprintf(buf, sizeof(buf), "%7.1f s | %8.1f MB (%.1f MB/s) | frames", elapsed_s, mb,
                elapsed_s > 0 ? mb / elapsed_s : 0.0);
  std::string line = buf;
  for (int64_t n : s.frames) line += " " + std::to_string(n);
  std::snprintf(buf, sizeof(buf), " | drops %lld", static_cast<long long>(s.DroppedTotal()));
  line += buf;
  if (s.DroppedTotal() > 0) {
    line += " (disk " + std::to_string(s.dropped_disk) + ", cameras";
    for (int64_t n : s.dropped_capture) line += " " + std::to_string(n);
    line += ")";
  }
  if (s.other_events > 0) line += " | poses+extrinsics " + std::to_string(s.other_events);
  line += " | " + std::to_string(s.files.size()) + (s.files.size() == 1 ? " file" : " files");
  return line;
}

// Prints the progress line: in place on a terminal, one line per call otherwise.
// The one progress scheme (progress_line.h): log lines go above the line.
class Progress {
 public:
  double period_s() const { return line_.tty() ? 0.25 : 1.0; }
  void Show(const std::string& line) { line_.Show(kPrefix + line); }
  void End() {}

 private:
  ProgressLine line_;
};

int RunRecord(const RecordArgs& args) {
  auto config = io::LoadRigConfig(args.config);
  if (!config) {
    std::cerr << kPrefix << config.error() << "\n";
    return kExitError;
  }
  const std::vector<std::string> names = config->CameraNames();
  pipeline::RecorderOptions options;
  options.image.encoding = *pipeline::ParseImageEncoding(args.image_encoding);  // CLI-checked
  options.image.jpeg_quality = args.jpeg_quality;
  options.log.split_bytes = static_cast<int64_t>(std::llround(args.split_mb * 1e6));
  options.log.overwrite = args.force;

  auto sources = pipeline::OpenCaptureSources(*config, args.fast, kPrefix, std::cerr);
  if (!sources) {
    std::cerr << kPrefix << sources.error() << "\n";
    return kExitError;
  }
  options.lossless = !sources->realtime;
  auto opened = pipeline::LogRecorder::Open(args.out, names, options);
  if (!opened) {
    std::cerr << kPrefix << opened.error() << "\n";
    return kExitError;
  }
  pipeline::LogRecorder& recorder = **opened;
  std::vector<std::unique_ptr<capture::CameraDevice>> devices;
  for (size_t i = 0; i < sources->devices.size(); ++i) {
    devices.push_back(recorder.Tap(std::move(sources->devices[i]), static_cast<int>(i)));
  }

  // With VO: the live pipeline publishes its poses on an in-process bus, recorded from there.
  std::unique_ptr<::lcm::LCM> bus;
  std::unique_ptr<lcm::SharedBus> shared_bus;
  PoseTap pose_tap;
  pose_tap.recorder = &recorder;
  std::unique_ptr<pipeline::Pipeline> pipeline;
  std::unique_ptr<pipeline::CaptureLoops> capture;
  if (args.no_vo) {
    capture = std::make_unique<pipeline::CaptureLoops>(std::move(devices));
  } else {
    bus = std::make_unique<::lcm::LCM>("memq://");
    if (!bus->good()) {
      std::cerr << kPrefix << "cannot open the in-process LCM bus (memq://)\n";
      return kExitError;
    }
    bus->subscribeFunction("RIGCAL_POSE_.*", &OnPose, &pose_tap);
    shared_bus = std::make_unique<lcm::SharedBus>(bus.get());
    pipeline::PipelineOptions pipeline_options;
    pipeline_options.lossless = options.lossless;
    pipeline =
        std::make_unique<pipeline::Pipeline>(names, std::move(devices), sources->models,
                                             config->online, pipeline_options, shared_bus.get());
  }
  const auto drain_bus = [&bus] {
    if (bus) {
      while (bus->handleTimeout(0) > 0) {
      }
    }
  };
  int64_t newest_t_ns = 0;
  const auto record_extrinsics = [&] {
    const pipeline::PipelineSnapshot snapshot = pipeline->Snapshot();
    for (const pipeline::CameraHealth& h : snapshot.cameras) {
      newest_t_ns = std::max(newest_t_ns, h.last_frame_t_ns);
    }
    if (snapshot.estimate.sets == 0) return;
    auto msg = lcm::EstimateToLcm(snapshot.estimate, newest_t_ns / 1000);
    if (!msg) return;
    auto bytes = lcm::EncodeMessage(lcm::kExtrinsicsChannel, names, *msg);
    if (bytes) recorder.Record(lcm::kExtrinsicsChannel, newest_t_ns / 1000, std::move(*bytes));
  };

  StopSignal stop_signal;
  lcm::CpuMeter cpu;
  const double cpu_start_s = lcm::ProcessCpuSeconds();
  const auto start = Clock::now();
  if (pipeline) pipeline->Start();
  if (capture) capture->Start();
  std::cerr << kPrefix << "recording " << names.size() << " cameras ("
            << ToString(options.image.encoding) << (args.no_vo ? "" : ", with VO poses") << ") to "
            << args.out << "; Ctrl-C stops cleanly\n";
  Progress progress;
  auto last_progress = start;
  auto last_extrinsics = start;
  const double extrinsics_period_s = 1.0 / config->publish.extrinsics_rate_hz;
  while (!stop_signal.flag().load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    drain_bus();
    const auto now = Clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (args.duration_s > 0 && elapsed >= args.duration_s) break;
    if (pipeline ? pipeline->Finished() : capture->Finished()) break;
    if (!recorder.Stats().error.empty()) break;  // the disk failed: reported below
    if (pipeline &&
        std::chrono::duration<double>(now - last_extrinsics).count() >= extrinsics_period_s) {
      record_extrinsics();
      last_extrinsics = now;
    }
    if (std::chrono::duration<double>(now - last_progress).count() >= progress.period_s()) {
      progress.Show(ProgressText(elapsed, recorder.Stats()));
      last_progress = now;
    }
  }
  if (pipeline) {
    pipeline->Stop();
    drain_bus();
    record_extrinsics();
  }
  if (capture) capture->Stop();
  if (sources->trigger) sources->trigger->Stop();  // after the cameras it exposes
  const Status stopped = recorder.Stop();
  const double elapsed = std::chrono::duration<double>(Clock::now() - start).count();
  const double cpu_percent = 100.0 * (lcm::ProcessCpuSeconds() - cpu_start_s) / elapsed;
  const pipeline::RecorderStats stats = recorder.Stats();
  progress.Show(ProgressText(elapsed, stats));
  progress.End();

  if (capture) {
    for (const std::string& problem : capture->Problems()) std::cerr << kPrefix << problem << "\n";
  }
  if (pipeline) {
    for (const pipeline::CameraHealth& h : pipeline->Snapshot().cameras) {
      if (h.dead)
        std::cerr << kPrefix << "camera '" << h.name << "' died: " << h.dead_reason << "\n";
    }
  }
  pipeline::ReportFolderProblems(sources->folders, kPrefix, std::cerr);
  pipeline::ReportTrigger(*sources, kPrefix, std::cerr);
  if (!stopped.ok()) {
    std::cerr << kPrefix << stopped.message() << "\n";
    return kExitError;
  }
  const double mb = static_cast<double>(stats.bytes) / 1e6;
  std::printf(
      "recorded %lld frames (%lld events, %.1f MB) in %.1f s to %zu file%s: %.2f MB/s, %.1f "
      "frames/s, CPU %.0f %% (100 = one core), dropped %lld\n",
      static_cast<long long>(stats.FramesTotal()), static_cast<long long>(stats.events), mb,
      elapsed, stats.files.size(), stats.files.size() == 1 ? "" : "s", mb / elapsed,
      static_cast<double>(stats.FramesTotal()) / elapsed, cpu_percent,
      static_cast<long long>(stats.DroppedTotal()));
  for (const std::string& file : stats.files) std::printf("  %s\n", file.c_str());
  return kExitOk;
}

}  // namespace

void RegisterRecord(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<RecordArgs>();
  CLI::App* cmd = app.add_subcommand(
      "record",
      "Record every camera of the configured source into an LCM log (lcm-logger format, plays in\n"
      "lcm-logplayer): RIGCAL_IMAGE_<camera> image_t per frame and, unless --no-vo, the VO poses\n"
      "(RIGCAL_POSE_<camera>) and the rig estimate (RIGCAL_EXTRINSICS) of the live pipeline.\n"
      "A progress line (MB, frames per camera, drops) refreshes in place on a terminal, one line\n"
      "per second otherwise. Every event is written whole and the log synced every second: after\n"
      "a crash or power loss it is readable up to its last complete event.");
  // A missing config is bad input (exit 1, named by the loader), not a usage error.
  cmd->add_option("--config", args->config, "Rig config YAML with a `source:` section")->required();
  cmd->add_option("-o,--out", args->out, "LCM log file to write")->required();
  cmd->add_option("--duration", args->duration_s, "Stop after this many seconds (0 = source end)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--image-encoding", args->image_encoding,
                  "raw (no CPU, 1 byte per pixel), png (lossless, smaller, CPU-heavy) or jpeg "
                  "(lossy, smallest)")
      ->check(CLI::IsMember({"raw", "png", "jpeg"}))
      ->capture_default_str();
  cmd->add_option("--jpeg-quality", args->jpeg_quality, "JPEG quality, 1..100")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--split-mb", args->split_mb,
                  "Start a new file before one would exceed this many MB (10^6 bytes); the files "
                  "are then named as lcm-logger -i names them: OUT.00, OUT.01, ... (0 = one file)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-vo", args->no_vo, "Record the images only (no VO, poses or extrinsics)");
  cmd->add_flag("--fast", args->fast,
                "Do not pace a simulated source in real time: record as fast as possible, "
                "without dropping frames");
  cmd->add_flag(
      "-f,--force", args->force,
      "Replace existing log files (each with the new log's first event, so a recording that "
      "records nothing leaves the old one)");
  cmd->footer(
      "Exit status: 0 recorded; 1 bad config, the log cannot be written (the message names the "
      "file), 2 usage.");
  cmd->callback([args, exit_code]() { *exit_code = RunRecord(*args); });
}

}  // namespace rigcal::cli
