// SPDX-License-Identifier: Apache-2.0
// `rigcal calib`: the online calibration node on an LCM bus (or replaying an LCM log, as
// `rigcal replay` does).
#include <iostream>
#include <memory>
#include <string>

#include "calib_node_run.h"
#include "commands.h"

namespace rigcal::cli {
namespace {

struct CalibArgs {
  NodeRunArgs run;
  pipeline::CalibNodeOptions node;
};

}  // namespace

void RegisterCalib(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<CalibArgs>();
  args->run.command = "calib";
  args->node.result_path = "rigcal_result.yaml";
  args->node.report_every_s = 10.0;
  CLI::App* cmd = app.add_subcommand(
      "calib",
      "Online calibration node: subscribes RIGCAL_POSE_<camera> (camera_pose_t from VO running\n"
      "anywhere on the LCM bus), matches poses by time, updates the rig estimate recursively and\n"
      "publishes RIGCAL_EXTRINSICS and RIGCAL_STATUS. Writes the result YAML on exit (Ctrl-C,\n"
      "SIGTERM, --duration or the end of a replayed --log; --log replays as `rigcal replay`\n"
      "does). Exit 0 every slave usable, 3 some slave not (or nothing received), 1 bad input.");
  AddNodeOptions(cmd, &args->run, &args->node);
  cmd->add_option("--lcm", args->node.lcm_url,
                  "LCM URL to listen and publish on (default: LCM's default udpm URL). It must "
                  "stay on this host (memq://, or udpm:// with ttl=0 and the group routed to lo) "
                  "unless --lcm-network is given");
  cmd->add_flag("--lcm-network", args->node.lcm_network,
                "Allow an LCM URL that other hosts reach (udpm:// with ttl > 0 or routed through "
                "a network link, tcpq:// to another host): poses from them are accepted");
  cmd->add_option("--log", args->node.log_path,
                  "Replay an LCM log file (lcm-logger format) instead of listening, losing "
                  "nothing, timers on log time; ends at its end (see `rigcal replay`)")
      ->excludes("--lcm");
  cmd->add_option("--publish-lcm", args->node.publish_url,
                  "With --log: LCM URL to publish on (e.g. file:///tmp/out.log?mode=w); default "
                  "none");
  cmd->add_option("--duration", args->node.duration_s,
                  "Stop after this many seconds (0 = never; live input)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--report-every", args->node.report_every_s,
                  "Seconds between status lines on stderr (log time with --log; 0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->default_val(10.0);
  cmd->callback([args, exit_code]() {
    // LCM's file provider plays a log at its own pace and drops what the estimator has not
    // taken: a replay must wait for it.
    if (args->node.lcm_url.rfind("file://", 0) == 0) {
      std::cerr << "rigcal calib: --lcm file://... would drop the sets the estimator is not "
                   "ready for; replay a log losslessly with `rigcal replay LOG --config ...` "
                   "(or `rigcal calib --log LOG`)\n";
      *exit_code = 2;
      return;
    }
    *exit_code = RunCalibNode(args->run, args->node);
  });
}

}  // namespace rigcal::cli
