// SPDX-License-Identifier: Apache-2.0
// `rigcal run`: the whole live pipeline on the config's source: capture -> VO per camera ->
// SyncBuffer -> RigEstimator -> LCM, owned by one CalibNode with a capture input (calib_node.h).
#include <memory>
#include <string>

#include "calib_node_run.h"
#include "commands.h"

namespace rigcal::cli {
namespace {

struct RunArgs {
  NodeRunArgs run;
  pipeline::CalibNodeOptions node;
};

void AddRunOptions(CLI::App* cmd, RunArgs* args) {
  pipeline::CalibNodeOptions& node = args->node;
  cmd->add_option("--lcm", node.publish_url,
                  "Publish RIGCAL_POSE_<camera>, RIGCAL_EXTRINSICS and RIGCAL_STATUS on this LCM "
                  "URL at the config's publish rates (default: no LCM); it must stay on this "
                  "host unless --lcm-network");
  cmd->add_flag("--lcm-network", node.lcm_network,
                "Allow an --lcm URL that other hosts reach (see `rigcal calib --help`)")
      ->needs("--lcm");
  cmd->add_option("--duration", node.duration_s, "Stop after this many seconds (0 = source end)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--eval", args->run.eval,
                "Simulated source: print the errors against the ground truth at the end");
  cmd->add_flag("--fast", node.fast,
                "Do not pace a simulated source in real time: run as fast as the VO allows, "
                "without dropping frames (timers then run on the frames' stamps)");
  cmd->add_option("--truth-out", node.truth_dir,
                  "Simulated source: write the ground truth (TUM per camera, truth.yaml) here");
  cmd->add_option("--poses-out", node.poses_dir,
                  "Write every VO pose of every camera to DIR/<camera>.txt (rigcal native format "
                  "with the scale segment column, read by `rigcal solve`)");
  cmd->add_option("--status-every", node.report_every_s,
                  "Seconds between status lines on stderr (0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->default_val(1.0);
  cmd->add_option("--camera-timeout", node.camera_timeout_s,
                  "A camera without frames, or an estimator without sets, for this many seconds "
                  "stops feeding the service watchdog")
      ->check(CLI::PositiveNumber)
      ->default_val(5.0);
}

}  // namespace

void RegisterRun(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<RunArgs>();
  args->run.command = "run";
  args->node.capture = true;
  CLI::App* cmd = app.add_subcommand(
      "run",
      "The live pipeline: capture from the configured source, monocular VO per camera, pose\n"
      "matching and the recursive rig estimator; a status line per second, LCM publishing with\n"
      "--lcm at the config's publish rates, the state saved every state.save_interval_s and on\n"
      "exit (--state / state.path; --resume continues from it), the result YAML on exit.\n"
      "Exit 3 when no slave could be calibrated.");
  AddNodeOptions(cmd, &args->run, &args->node);
  AddRunOptions(cmd, args.get());
  cmd->callback([args, exit_code]() {
    pipeline::CalibNodeOptions node = args->node;
    node.evaluate = args->run.eval || args->run.json;
    *exit_code = RunCalibNode(args->run, node);
  });
}

}  // namespace rigcal::cli
