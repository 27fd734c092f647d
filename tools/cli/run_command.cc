// `rigcal run`: the whole live pipeline on a configured source: capture -> VO per camera ->
// SyncBuffer -> RigEstimator -> LCM, with a status line per second.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <thread>

#include "commands.h"
#include "exit_codes.h"
#include "provenance_args.h"
#include "rigcal/base/format.h"
#include "rigcal/base/logging.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/ground_truth_files.h"
#include "rigcal/io/result_json.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/lcm/bus_exposure.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/lcm/shared_bus.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/calib_node.h"
#include "rigcal/pipeline/capture_sources.h"
#include "rigcal/pipeline/online_replay.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/pipeline/run_evaluation.h"
#include "rigcal/sim/simulated_rig.h"
#include "stop_signal.h"

namespace rigcal::cli {
namespace {

struct RunArgs {
  std::string config;
  std::string lcm_url;
  bool lcm_network = false;
  double duration_s = 0.0;
  bool eval = false;
  bool json = false;
  bool fast = false;
  std::string out = "rigcal_result.yaml";
  std::string truth_dir;
  std::string poses_dir;
  double status_every_s = 1.0;
};

const char* VoStateShort(vo::VoState state) {
  switch (state) {
    case vo::VoState::kInitialising:
      return "init";
    case vo::VoState::kTracking:
      return "trk";
    case vo::VoState::kLost:
      return "lost";
  }
  return "?";
}

// One line: time, per camera fps / VO state / segment / VO ms, sets, per slave estimate.
std::string StatusLine(double t_s, const pipeline::PipelineSnapshot& s,
                       const std::vector<int64_t>& frames_before, double period_s) {
  std::ostringstream line;
  char buf[160];
  std::snprintf(buf, sizeof(buf), "%6.1fs", t_s);
  line << buf;
  for (size_t i = 0; i < s.cameras.size(); ++i) {
    const pipeline::CameraHealth& h = s.cameras[i];
    const double fps = period_s > 0 ? (h.frames_processed - frames_before[i]) / period_s : 0.0;
    if (h.dead) {
      line << " | " << h.name << " DEAD";
      continue;
    }
    std::snprintf(buf, sizeof(buf), " | %s %4.1ffps %s s%d %.1fms", h.name.c_str(), fps,
                  VoStateShort(h.vo_state), h.segment, h.vo_ms_median);
    line << buf;
    if (h.dropped_backlog > 0) line << " drop" << h.dropped_backlog;
  }
  line << " | sets " << s.estimate.sets;
  for (size_t i = 0; i < s.estimate.rig.slaves.size(); ++i) {
    const SlaveCalibration& slave = s.estimate.rig.slaves[i];
    if (slave.solved()) {
      std::snprintf(buf, sizeof(buf), " | %s C=(%.2f %.2f %.2f) u ±%s, rot ±%s° %d mot",
                    slave.name.c_str(), slave.estimate.C.x(), slave.estimate.C.y(),
                    slave.estimate.C.z(), SigmaText(slave.pos_std.maxCoeff(), 2).c_str(),
                    SigmaText(slave.rot_std_deg, 2).c_str(), slave.motions.used);
      line << buf;
    } else {
      line << " | " << slave.name << " " << slave.motions.used << " mot";
    }
    if (i < s.estimate.online.size()) {
      line << " [" << StateText(slave.state, s.estimate.online[i].flags) << "]";
    }
  }
  return line.str();
}

void PublishStatus(lcm::SharedBus* bus, const pipeline::PipelineSnapshot& s,
                   std::vector<lcm::StampRate>* rates, int32_t capacity, lcm::CpuMeter* cpu,
                   const std::vector<std::string>& names) {
  std::vector<lcm::CameraStatusInput> cameras;
  for (size_t i = 0; i < s.cameras.size(); ++i) {
    const pipeline::CameraHealth& h = s.cameras[i];
    lcm::CameraStatusInput c = pipeline::StatusInputOf(h);
    c.fps = (*rates)[i].Update(h.frames_processed, h.last_frame_t_ns, -1);
    cameras.push_back(c);
  }
  const int64_t utime = std::chrono::duration_cast<std::chrono::microseconds>(
                            std::chrono::steady_clock::now().time_since_epoch())
                            .count();
  const rig_status_t msg =
      lcm::MakeRigStatus(cameras, s.sync, capacity, s.estimate, cpu->Sample(), utime);
  if (auto bytes = lcm::EncodeMessage(lcm::kStatusChannel, names, msg)) {
    bus->Publish(lcm::kStatusChannel, *bytes);
  }
  if (auto extrinsics = lcm::EstimateToLcm(s.estimate, utime)) {
    if (auto bytes = lcm::EncodeMessage(lcm::kExtrinsicsChannel, names, *extrinsics)) {
      bus->Publish(lcm::kExtrinsicsChannel, *bytes);
    }
  }
}

// Writes every recorded VO pose of camera i to <dir>/<name>.txt in the rigcal native format
// (`t_ns qw qx qy qz Cx Cy Cz segment`), which `rigcal solve` reads.
Status WritePoses(const std::string& dir, const std::vector<std::string>& names,
                  const pipeline::Pipeline& pipeline) {
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
    if (Status status = io::WriteTrajectoryNative(path, trajectory); !status.ok()) {
      return status;
    }
  }
  return Status::Ok();
}

int RunRun(const RunArgs& args) {
  auto log = ModuleLogger("tools");
  auto config = io::LoadRigConfig(args.config);
  if (!config) {
    std::cerr << "rigcal run: " << config.error() << "\n";
    return kExitError;
  }
  const std::vector<std::string> names = config->CameraNames();
  if (args.eval && !config->simulated_source) {
    std::cerr << "rigcal run: --eval needs a simulated source (ground truth)\n";
    return kExitError;
  }
  auto sources = pipeline::OpenCaptureSources(*config, args.fast, "rigcal run: ", std::cerr);
  if (!sources) {
    std::cerr << "rigcal run: " << sources.error() << "\n";
    return kExitError;
  }
  const std::optional<sim::SimulatedRig>& rig = sources->rig;
  const bool realtime = sources->realtime;
  if (rig && !args.truth_dir.empty()) {
    if (const Status status = io::WriteGroundTruth(rig->GroundTruth(), args.truth_dir);
        !status.ok()) {
      std::cerr << "rigcal run: " << status.message() << "\n";
      return kExitError;
    }
  }
  std::unique_ptr<::lcm::LCM> bus;
  if (!args.lcm_url.empty()) {
    bus = std::make_unique<::lcm::LCM>(args.lcm_url);
    if (!bus->good()) {
      std::cerr << "rigcal run: " << args.lcm_url << ": cannot open LCM\n";
      return kExitError;
    }
    if (!args.lcm_network) {
      if (const Status status = lcm::CheckBusStaysOnHost(args.lcm_url); !status.ok()) {
        std::cerr << "rigcal run: " << status.message() << "\n";
        return kExitError;
      }
    }
  }
  // The VO threads publish poses and this thread the status on the same bus.
  std::unique_ptr<lcm::SharedBus> shared_bus;
  if (bus) shared_bus = std::make_unique<lcm::SharedBus>(bus.get());
  pipeline::PipelineOptions options;
  options.lossless = !realtime;
  options.record_poses = (rig.has_value() && (args.eval || args.json)) || !args.poses_dir.empty();
  pipeline::Pipeline pipeline(names, std::move(sources->devices), sources->models, config->online,
                              options, shared_bus.get());

  StopSignal stop_signal;
  const auto start = std::chrono::steady_clock::now();
  pipeline.Start();
  std::cerr << "rigcal run: running; Ctrl-C stops cleanly\n";
  std::vector<int64_t> frames_before(names.size(), 0);
  std::vector<lcm::StampRate> rates(names.size());
  auto last_status = start;
  lcm::CpuMeter cpu;
  const int32_t capacity = config->online.sync.capacity * static_cast<int32_t>(names.size());
  bool trigger_failure_told = false;
  while (!pipeline.Finished() && !stop_signal.flag().load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (sources->trigger && !trigger_failure_told) {
      if (const std::string problem = sources->trigger->problem(); !problem.empty()) {
        std::cerr << "rigcal run: trigger link failed: " << problem
                  << " (frames now come without trigger pulses)\n";
        trigger_failure_told = true;
      }
    }
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (args.duration_s > 0 && elapsed >= args.duration_s) break;
    const double period = std::chrono::duration<double>(now - last_status).count();
    if (period >= (args.status_every_s > 0 ? args.status_every_s : 1.0)) {
      const pipeline::PipelineSnapshot snapshot = pipeline.Snapshot();
      if (args.status_every_s > 0)
        std::cerr << StatusLine(elapsed, snapshot, frames_before, period) << "\n";
      if (shared_bus) PublishStatus(shared_bus.get(), snapshot, &rates, capacity, &cpu, names);
      for (size_t i = 0; i < names.size(); ++i) {
        frames_before[i] = snapshot.cameras[i].frames_processed;
      }
      last_status = now;
    }
  }
  pipeline.Stop();
  if (sources->trigger) sources->trigger->Stop();  // after the cameras it exposes
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const pipeline::PipelineSnapshot final_state = pipeline.Snapshot();
  if (shared_bus) PublishStatus(shared_bus.get(), final_state, &rates, capacity, &cpu, names);
  const RigCalibration& result = final_state.estimate.rig;

  // What happened to the cameras.
  for (const pipeline::CameraHealth& h : final_state.cameras) {
    if (h.dead)
      std::cerr << "rigcal run: camera '" << h.name << "' died: " << h.dead_reason << "\n";
    if (h.dropped_backlog > 0) {
      std::cerr << "rigcal run: camera '" << h.name << "': " << h.dropped_backlog
                << " frames dropped because its VO fell behind\n";
    }
  }
  pipeline::ReportFolderProblems(sources->folders, "rigcal run: ", std::cerr);
  pipeline::ReportCaptureStats(sources->v4l2, "rigcal run: ", std::cerr);
  pipeline::ReportTrigger(*sources, "rigcal run: ", std::cerr);
  std::fprintf(stderr, "rigcal run: %.1f s, %llu sets; RSS %.0f MB\n", elapsed,
               static_cast<unsigned long long>(final_state.estimate.sets),
               static_cast<double>(lcm::ResidentSetBytes()) / (1 << 20));
  if (!args.out.empty() && final_state.estimate.sets == 0 && std::filesystem::exists(args.out)) {
    // A run that calibrated nothing never replaces an earlier result.
    std::cerr << "rigcal run: calibrated nothing: " << args.out << " left as it was\n";
  } else if (!args.out.empty()) {
    const std::string text =
        io::ResultToYaml(result) + io::ProvenanceToYaml(ProvenanceOf({}, args.config, false));
    if (const Status status = io::WriteFileAtomically(args.out, text); !status.ok()) {
      std::cerr << "rigcal run: " << status.message() << "\n";
      return kExitError;
    }
    log->info("result written to {}", args.out);
  }

  if (!args.poses_dir.empty()) {
    if (const Status status = WritePoses(args.poses_dir, names, pipeline); !status.ok()) {
      std::cerr << "rigcal run: " << status.message() << "\n";
      return kExitError;
    }
  }
  if (rig && !args.truth_dir.empty() && !args.poses_dir.empty()) {
    // In real time the devices' stamps start with the rig clock: rewrite the truth now that
    // it runs, so its stamps match the written poses (before the run they count from 0).
    if (const Status status = io::WriteGroundTruth(rig->GroundTruth(), args.truth_dir);
        !status.ok()) {
      std::cerr << "rigcal run: " << status.message() << "\n";
      return kExitError;
    }
  }

  bool any_usable = false;
  for (const SlaveCalibration& slave : result.slaves) any_usable = any_usable || slave.usable();
  std::optional<pipeline::RunEvaluation> evaluation;
  if (rig && (args.eval || args.json)) {
    std::vector<std::vector<CameraPose>> poses;
    for (size_t i = 0; i < names.size(); ++i) {
      poses.push_back(pipeline.RecordedPoses(static_cast<int>(i)));
    }
    auto e = pipeline::EvaluateRun(*rig, poses, result);
    if (e) {
      evaluation = *e;
    } else {
      std::cerr << "rigcal run: " << e.error() << "\n";
    }
  }
  if (args.json) {
    std::map<std::string, Similarity> truth;
    if (evaluation) {
      for (const pipeline::SlaveEvaluation& e : evaluation->slaves)
        truth[e.name] = e.truth_master_units;
    }
    std::optional<io::TruthAlignment> alignment;
    if (evaluation) alignment = pipeline::AlignmentOf(*evaluation);
    nlohmann::json json =
        io::ResultToJson(result, evaluation ? &truth : nullptr, alignment ? &*alignment : nullptr);
    json["provenance"] = io::ProvenanceToJson(ProvenanceOf({}, args.config, false));
    std::cout << json.dump(2) << "\n";
  } else {
    std::cout << io::FormatResultTable(result, nullptr);
    if (!any_usable) {
      std::cout << "insufficient motion: no slave could be calibrated (see the messages above; "
                   "the rig must rotate about at least two axes, or move, while the cameras "
                   "track)\n";
    }
    if (args.eval && evaluation) std::cout << pipeline::FormatEvaluation(*evaluation);
  }
  std::vector<SlaveState> states;
  for (const SlaveCalibration& slave : result.slaves) states.push_back(slave.state);
  return ExitCodeFor(states);  // 0 every slave usable, 3 otherwise (slave_state.h)
}

}  // namespace

void RegisterRun(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "The live pipeline: capture from the configured source, monocular VO per camera, pose\n"
      "matching and the recursive rig estimator; a status line per second, LCM publishing with\n"
      "--lcm, the result YAML on exit. Exit 3 when no slave could be calibrated.");
  cmd->add_option("--config", args->config, "Rig config YAML with a `source:` section")->required();
  cmd->add_option("--lcm", args->lcm_url,
                  "Publish RIGCAL_POSE_<camera>, RIGCAL_EXTRINSICS and RIGCAL_STATUS on this LCM "
                  "URL (default: no LCM); it must stay on this host unless --lcm-network");
  cmd->add_flag("--lcm-network", args->lcm_network,
                "Allow an --lcm URL that other hosts reach (see `rigcal calib --help`)")
      ->needs("--lcm");
  cmd->add_option("--duration", args->duration_s, "Stop after this many seconds (0 = source end)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--eval", args->eval,
                "Simulated source: print the errors against the ground truth at the end");
  cmd->add_flag("--json", args->json,
                "Print the final result as JSON (rigcal solve --json schema, with \"errors\" for a "
                "simulated source)");
  cmd->add_flag("--fast", args->fast,
                "Do not pace a simulated source in real time: run as fast as the VO allows, "
                "without dropping frames");
  cmd->add_option("-o,--out", args->out, "Result YAML written on exit (atomically)")
      ->default_val("rigcal_result.yaml");
  cmd->add_option("--truth-out", args->truth_dir,
                  "Simulated source: write the ground truth (TUM per camera, truth.yaml) here");
  cmd->add_option("--poses-out", args->poses_dir,
                  "Write every VO pose of every camera to DIR/<camera>.txt (rigcal native format "
                  "with the scale segment column, read by `rigcal solve`)");
  cmd->add_option("--status-every", args->status_every_s, "Seconds between status lines (0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->default_val(1.0);
  cmd->callback([args, exit_code]() { *exit_code = RunRun(*args); });
}

}  // namespace rigcal::cli
