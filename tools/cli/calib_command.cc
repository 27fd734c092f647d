// `rigcal calib`: the online calibration node on an LCM bus (or replaying an LCM log).
#include <csignal>
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "rigcal/calib/logging.h"
#include "rigcal/io/result_json.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/calib_node.h"
#include "stop_signal.h"

namespace rigcal::cli {
namespace {

constexpr int kExitOk = 0;
constexpr int kExitError = 1;

struct CalibArgs {
  std::string config;
  std::string lcm_url;
  std::string log;
  std::string publish_url;
  std::string out = "rigcal_result.yaml";
  std::string state;
  bool resume = false;
  double duration_s = 0.0;
  double report_every_s = 10.0;
  bool json = false;
};

int RunCalib(const CalibArgs& args) {
  auto log = ModuleLogger("tools");
  auto config = tools::LoadRigConfig(args.config);
  if (!config) {
    std::cerr << "rigcal calib: " << config.error() << "\n";
    return kExitError;
  }
  tools::CalibNodeOptions options;
  options.lcm_url = args.lcm_url;
  options.log_path = args.log;
  options.publish_url = args.publish_url;
  options.result_path = args.out;
  options.state_path = args.state;
  options.resume = args.resume;
  options.duration_s = args.duration_s;
  options.report_every_s = args.report_every_s;
  // With true mountings in the config (simulations), the result also shows the errors.
  std::map<std::string, Similarity> truth;
  for (const tools::CameraConfig& camera : config->cameras) {
    if (camera.truth) truth[camera.name] = *camera.truth;
  }
  const std::map<std::string, Similarity>* truth_ptr = truth.empty() ? nullptr : &truth;
  tools::CalibNode node(std::move(*config), options);
  if (const Status status = node.Open(); !status.ok()) {
    std::cerr << "rigcal calib: " << status.message() << "\n";
    return kExitError;
  }
  StopSignal stop_signal;
  log->info("listening for RIGCAL_POSE_<camera>; stop with Ctrl-C (SIGINT) or SIGTERM");
  const tools::CalibNodeSummary summary = node.Run(stop_signal.flag());
  if (stop_signal.received() != 0) {
    log->info("signal {} received: stopped cleanly", stop_signal.received());
  }
  log->info("sync: {}", summary.sync.BriefReport());
  log->info("decoder: {}; unknown cameras: {}", summary.decode.Summary(), summary.unknown_channel);
  if (!summary.log_problem.empty()) std::cerr << "rigcal calib: " << summary.log_problem << "\n";
  if (args.json) {
    std::cout << tools::ResultToJson(summary.estimate.rig, truth_ptr).dump(2) << "\n";
  } else {
    std::cout << tools::FormatResultTable(summary.estimate.rig, truth_ptr);
  }
  if (!args.out.empty()) log->info("result written to {}", args.out);
  return summary.errors.empty() ? kExitOk : kExitError;
}

}  // namespace

void RegisterCalib(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<CalibArgs>();
  CLI::App* cmd = app.add_subcommand(
      "calib",
      "Online calibration node: subscribes RIGCAL_POSE_<camera> (camera_pose_t from VO running\n"
      "anywhere on the LCM bus), matches poses by time, updates the rig estimate recursively and\n"
      "publishes RIGCAL_EXTRINSICS and RIGCAL_STATUS. Writes the result YAML on exit (Ctrl-C,\n"
      "SIGTERM, --duration or the end of a replayed --log).");
  cmd->add_option("--config", args->config, "Rig config YAML (see config/README.md)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--lcm", args->lcm_url,
                  "LCM URL to listen and publish on (default: LCM's default udpm URL)");
  cmd->add_option("--log", args->log,
                  "Replay an LCM log file (lcm-logger) instead of listening; ends at its end")
      ->check(CLI::ExistingFile)
      ->excludes("--lcm");
  cmd->add_option("--publish-lcm", args->publish_url,
                  "With --log: LCM URL to publish on (e.g. file:///tmp/out.log?mode=w); default "
                  "none");
  cmd->add_option("--out", args->out, "Result YAML written on exit (atomically)")
      ->default_val("rigcal_result.yaml");
  cmd->add_option("--state", args->state,
                  "Estimator state file (overrides state.path of the config); saved atomically "
                  "every state.save_interval_s and on stop");
  cmd->add_flag("--resume", args->resume,
                "Continue from the state file; a missing, corrupt or foreign one is reported and "
                "ignored");
  cmd->add_option("--duration", args->duration_s, "Stop after this many seconds (0 = never)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--report-every", args->report_every_s,
                  "Seconds between status lines on stderr (0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->default_val(10.0);
  cmd->add_flag("--json", args->json,
                "Print the final result as JSON (rigcal solve --json schema)");
  cmd->callback([args, exit_code]() { *exit_code = RunCalib(*args); });
}

}  // namespace rigcal::cli
