// SPDX-License-Identifier: Apache-2.0
#include "calib_node_run.h"

#include <cmath>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "camchain_args.h"
#include "command_line.h"
#include "exit_codes.h"
#include "no_sets_reason.h"
#include "provenance_args.h"
#include "replay_progress.h"
#include "rigcal/base/logging.h"
#include "rigcal/io/result_json.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "service_notifier.h"
#include "stop_signal.h"
#include "truth_args.h"

namespace rigcal::cli {
namespace {

// "a (12), b (3)" of the channels a replay skipped.
std::string ChannelList(const std::map<std::string, int64_t>& channels) {
  std::ostringstream text;
  for (const auto& [channel, count] : channels) {
    text << (text.tellp() > 0 ? ", " : "") << channel << " (" << count << ")";
  }
  return text.str();
}

}  // namespace

void AddNodeOptions(CLI::App* cmd, NodeRunArgs* run, pipeline::CalibNodeOptions* node) {
  cmd->add_option("--config", run->config,
                  "Rig config YAML (see docs/config.md; camera models for image logs)")
      ->required();
  cmd->add_option("-o,--out", node->result_path, "Result YAML written at the end (atomically)")
      ->default_val("rigcal_result.yaml");
  cmd->add_option("--camchain", run->camchain,
                  "Also write a Kalibr camchain YAML: the config's intrinsics, T_cn_cnm1 in\n"
                  "metres for a metric master, else in master units (rigcal_translation_unit)");
  cmd->add_flag("--json", run->json,
                "Print the final result as JSON on stdout (rigcal solve --json schema)");
  cmd->add_option("--state", node->state_path,
                  "Estimator state file (overrides state.path of the config); saved atomically "
                  "every state.save_interval_s (of log time in a replay) and at the end");
  cmd->add_flag("--resume", node->resume,
                "Continue from the state file; a missing, corrupt or foreign one is reported and "
                "ignored");
}

namespace {

// What the run did, for the journal: signals, sync, decoder, the log, the devices.
void LogSummary(const NodeRunArgs& args, const pipeline::CalibNodeOptions& options,
                const pipeline::CalibNodeSummary& summary, int signal) {
  auto log = ModuleLogger("tools");
  const std::string prefix = "rigcal " + args.command + ": ";
  if (signal != 0) log->info("signal {} received: stopped cleanly", signal);
  log->info("sync: {}", summary.sync.BriefReport());
  if (!options.capture) {
    log->info("decoder: {}; unknown cameras: {}", summary.decode.Summary(),
              summary.unknown_channel);
  }
  for (const std::string& line : summary.capture_report) std::cerr << prefix << line << "\n";
  if (!options.log_path.empty()) {
    log->info("log: {} events, {:.1f} s of log time, replayed from its {}", summary.log_events,
              summary.log_span_s, summary.image_replay ? "images through VO" : "poses");
    if (!summary.skipped_channels.empty()) {
      log->info("channels not replayed: {}", ChannelList(summary.skipped_channels));
    }
  }
  if (!options.publish_url.empty() && !summary.publish_failed) {
    log->info("published {} RIGCAL_EXTRINSICS, {} RIGCAL_STATUS on {}",
              summary.extrinsics_published, summary.status_published, options.publish_url);
  }
  if (!summary.log_problem.empty()) std::cerr << prefix << summary.log_problem << "\n";
}

// The errors against a truth when one is known: the simulated source's evaluation (run), or
// the config's true mountings with the master unit fitted to them (calib, replay;
// truth_comparison.h).
struct TruthView {
  std::map<std::string, Similarity> truth;
  std::optional<io::TruthAlignment> alignment;
};

TruthView TruthOf(const NodeRunArgs& args, const io::RigConfig& config,
                  const pipeline::CalibNodeSummary& summary) {
  TruthView view;
  if (summary.evaluation) {
    for (const pipeline::SlaveEvaluation& e : summary.evaluation->slaves) {
      view.truth[e.name] = e.truth_master_units;
    }
    view.alignment = pipeline::AlignmentOf(*summary.evaluation);
    return view;
  }
  if (args.command == "run") return view;
  TruthFiles files;
  for (const io::CameraConfig& camera : config.cameras) {
    if (camera.truth) files.mountings[camera.name] = *camera.truth;
  }
  if (files.mountings.empty()) return view;
  auto compared = CompareRunWithTruth(summary.estimate.rig, files, io::TruthUnit::kAuto, {});
  if (compared) {
    view.truth = compared->truth_master_units;
    view.alignment = compared->alignment;
  }
  return view;
}

bool MasterIsMetric(const io::RigConfig& config) {
  return !config.cameras.empty() && config.cameras.front().metric;
}

// Where the result comes from (io/provenance.h): this rigcal, the command line, the log replayed
// and the config, with their sizes and hashes. In the JSON and at the end of the result YAML.
io::Provenance NodeProvenance(const NodeRunArgs& args, const io::RigConfig& config,
                              const pipeline::CalibNodeOptions& options) {
  return ProvenanceOf({options.log_path}, args.config, MasterIsMetric(config));
}

// The result on stdout: JSON (with its provenance) or the table (with the errors against a
// truth when known).
void PrintResult(const NodeRunArgs& args, const io::RigConfig& config,
                 const pipeline::CalibNodeOptions& options,
                 const pipeline::CalibNodeSummary& summary) {
  const RigCalibration& result = summary.estimate.rig;
  const TruthView view = TruthOf(args, config, summary);
  const std::map<std::string, Similarity>* truth_ptr = view.truth.empty() ? nullptr : &view.truth;
  const io::TruthAlignment* alignment = view.alignment ? &*view.alignment : nullptr;
  if (args.json) {
    nlohmann::json json = io::ResultToJson(result, truth_ptr, alignment);
    json["provenance"] = io::ProvenanceToJson(NodeProvenance(args, config, options));
    std::cout << json.dump(2) << "\n";
  } else if (args.command == "run") {
    std::cout << io::FormatResultTable(result, nullptr);
    bool any_usable = false;
    for (const SlaveCalibration& slave : result.slaves) any_usable |= slave.usable();
    if (!any_usable) {
      std::cout << "insufficient motion: no slave could be calibrated (see the messages above; "
                   "the rig must rotate about at least two axes, or move, while the cameras "
                   "track)\n";
    }
    if (args.eval && summary.evaluation) {
      std::cout << pipeline::FormatEvaluation(*summary.evaluation);
    }
  } else {
    std::cout << io::FormatResultTable(result, truth_ptr, alignment);
  }
  std::cout.flush();
}

// Files, errors and states after the result: the exit code.
int ExitCode(const NodeRunArgs& args, const io::RigConfig& config,
             const pipeline::CalibNodeOptions& options, const pipeline::CalibNodeSummary& summary) {
  auto log = ModuleLogger("tools");
  const std::string prefix = "rigcal " + args.command + ": ";
  const RigCalibration& result = summary.estimate.rig;
  if (summary.result_written) log->info("result written to {}", options.result_path);
  for (const std::string& kept : summary.kept_files) {
    std::cerr << prefix << "calibrated nothing: " << kept << " left as it was\n";
  }
  if (!args.camchain.empty()) {
    if (const Status status =
            WriteResultCamchain(args.camchain, result, IntrinsicsOf(config),
                                MasterIsMetric(config) ? 1.0 : std::nan(""), "metric master", *log);
        !status.ok()) {
      std::cerr << prefix << status.message() << "\n";
      return kExitError;
    }
  }
  if (!summary.errors.empty()) {
    for (const std::string& error : summary.errors) std::cerr << prefix << error << "\n";
    return kExitError;
  }
  if (summary.estimate.sets == 0 && !options.capture) {
    std::cerr << prefix << NoSetsReason(options.log_path, config.CameraNames(), summary) << "\n";
  }
  std::vector<SlaveState> states;
  for (const SlaveCalibration& slave : result.slaves) {
    states.push_back(slave.state);
    if (!slave.usable()) {
      // The message may start with the state already ("initialising: 3 motions so far").
      const std::string state(ToString(slave.state));
      const bool said = slave.message.rfind(state + ":", 0) == 0;
      std::cerr << prefix << slave.name << ": " << (said ? "" : state + ": ") << slave.message
                << "\n";
    }
  }
  return ExitCodeFor(states);  // 0 every slave usable, 3 otherwise (slave_state.h)
}

}  // namespace

int RunCalibNode(const NodeRunArgs& args, pipeline::CalibNodeOptions options) {
  auto log = ModuleLogger("tools");
  const std::string prefix = "rigcal " + args.command + ": ";
  auto config = io::LoadRigConfig(args.config);
  if (!config) {
    std::cerr << prefix << config.error() << "\n";
    return kExitError;
  }
  const io::RigConfig loaded = *config;
  options.result_provenance = io::ProvenanceToYaml(NodeProvenance(args, loaded, options));
  if (args.eval && !loaded.simulated_source) {
    std::cerr << prefix << "--eval needs a simulated source (ground truth)\n";
    return kExitError;
  }
  std::unique_ptr<ReplayProgressDisplay> display;
  if (args.progress && !QuietRequested() && !options.log_path.empty()) {
    display = std::make_unique<ReplayProgressDisplay>("rigcal " + args.command);
    options.on_progress = [&display](const pipeline::ReplayProgress& p) { display->Update(p); };
  }
  // Under systemd (config/systemd/rigcal.service, rigcal-run.service): READY=1 once listening
  // or capturing, the watchdog from the receive loop or while frames flow.
  ServiceNotifier service;
  const bool live = options.log_path.empty();
  if (live) options.on_tick = [&service] { service.Tick(); };
  // Before opening (a replay's VO, a device, the log take seconds on a slow machine): a signal
  // then still ends the command cleanly, with what it has.
  StopSignal stop_signal;
  pipeline::CalibNode node(std::move(*config), options);
  if (const Status status = node.Open(); !status.ok()) {
    std::cerr << prefix << status.message() << "\n";
    return kExitError;
  }
  if (live && !options.capture) {
    log->info("listening for RIGCAL_POSE_<camera>; stop with Ctrl-C (SIGINT), SIGTERM or SIGHUP");
  }
  if (live) service.Ready(options.capture ? "capturing" : "listening for RIGCAL_POSE_<camera>");
  const pipeline::CalibNodeSummary summary = node.Run(stop_signal.flag());
  if (live) service.Stopping();
  LogSummary(args, options, summary, stop_signal.received());
  if (!options.log_path.empty() && summary.log_events == 0 && !summary.log_problem.empty()) {
    // Damaged at byte 0: not an LCM log at all, bad input like a missing file.
    std::cerr << prefix << options.log_path << " is not an LCM log (lcm-logger format)\n";
    return kExitError;
  }
  PrintResult(args, loaded, options, summary);
  return ExitCode(args, loaded, options, summary);
}

}  // namespace rigcal::cli
