// SPDX-License-Identifier: Apache-2.0
// `rigcal replay`: an LCM log through the calibration, losing nothing, timers on log time.
#include <memory>
#include <string>

#include "calib_node_run.h"
#include "commands.h"

namespace rigcal::cli {
namespace {

struct ReplayArgs {
  NodeRunArgs run;
  pipeline::CalibNodeOptions node;
  bool fast = false;
  bool no_progress = false;
};

}  // namespace

void RegisterReplay(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<ReplayArgs>();
  args->run.command = "replay";
  CLI::App* cmd = app.add_subcommand(
      "replay",
      "Replays an LCM log (lcm-logger format) through the calibration. A log of images\n"
      "(RIGCAL_IMAGE_<camera>) runs through the live pipeline: VO per camera -> sync ->\n"
      "estimator; a log of poses (RIGCAL_POSE_<camera>) runs from the pose channels. Nothing\n"
      "is dropped (the reader waits for the VO and the estimator), so the same log gives the\n"
      "same result bit for bit, and a recorded live run replays to the result it gave when it\n"
      "dropped nothing. Every timer (publish, status, state save, refinement) runs on log time:\n"
      "--publish-lcm file://... holds the whole history of RIGCAL_EXTRINSICS and RIGCAL_STATUS.\n"
      "A truncated or corrupt log is replayed up to the damage (the byte offset is reported).\n"
      "Exit 0 every slave usable, 3 some slave not (or nothing in the log for the config's\n"
      "cameras), 1 bad input, 2 usage.");
  cmd->add_option("log", args->node.log_path, "The LCM log file")->required();
  AddNodeOptions(cmd, &args->run, &args->node);
  cmd->add_option("--speed", args->node.replay.speed,
                  "Pace by log time at this multiple of real time (default: as fast as possible)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--fast", args->fast, "As fast as possible, losing nothing (the default)")
      ->excludes("--speed");
  cmd->add_option("--from", args->node.replay.from_s,
                  "Start at this many seconds of log time after the first message")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--to", args->node.replay.to_s,
                  "Stop at this many seconds of log time after the first message")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--poses-only", args->node.replay.poses_only,
                "Replay the pose channels even when the log has images");
  cmd->add_option("--publish-lcm", args->node.publish_url,
                  "Publish RIGCAL_EXTRINSICS and RIGCAL_STATUS (utime = log time; and the VO's "
                  "RIGCAL_POSE_<camera> of an image log) on this LCM URL, e.g. "
                  "file:///tmp/out.lcmlog?mode=w");
  cmd->add_option("--report-every", args->node.report_every_s,
                  "Seconds of log time between status lines on stderr (0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->default_val(0.0);
  cmd->add_flag("--no-progress", args->no_progress,
                "No progress display (default: a bar with the ETA on a terminal, a line every "
                "5 s otherwise, on stderr)");
  cmd->callback([args, exit_code]() {
    if (args->node.replay.to_s >= 0.0 && args->node.replay.to_s < args->node.replay.from_s) {
      throw CLI::ValidationError("--to", "must not be before --from");
    }
    args->run.progress = !args->no_progress;
    *exit_code = RunCalibNode(args->run, args->node);
  });
}

}  // namespace rigcal::cli
