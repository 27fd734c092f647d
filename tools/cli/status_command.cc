// SPDX-License-Identifier: Apache-2.0
// `rigcal status`: the headless monitor of a running calibrator (RIGCAL_STATUS and
// RIGCAL_EXTRINSICS on an LCM bus).
#include <sys/ioctl.h>
#include <unistd.h>

#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "rigcal/monitor/status_monitor.h"
#include "stop_signal.h"

namespace rigcal::cli {
namespace {

// Columns of the terminal on stdout, 0 when unknown.
int TerminalWidth() {
  winsize size{};
  if (ioctl(STDOUT_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 0) return size.ws_col;
  return 0;
}

}  // namespace

void RegisterStatus(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<monitor::StatusRunOptions>();
  CLI::App* cmd = app.add_subcommand(
      "status",
      "Headless status monitor: listens to RIGCAL_STATUS and RIGCAL_EXTRINSICS of a running\n"
      "`rigcal calib` / `rigcal run` and shows per camera fps, drops by cause, VO state, segment\n"
      "and pose age; the sync buffer; per slave the estimate, its sigma (\"unknown\" when\n"
      "unknown), motions used and state; CPU and RSS of the calibrator; the age of the newest\n"
      "messages. On a terminal a dashboard refreshed in place (ANSI, works over SSH), else plain\n"
      "lines per RIGCAL_STATUS. Ctrl-C ends it.\n"
      "--once prints one snapshot and exits with the rig's health: 0 converged, 1 still\n"
      "converging, 2 decalibration alarm, 3 no data within --timeout (or LCM cannot be opened).");
  cmd->add_option("--lcm", options->url,
                  "LCM URL to listen on (default: LCM's default udpm URL; file:///log?speed=0 "
                  "reads a log); it must stay on this host unless --lcm-network");
  cmd->add_flag("--lcm-network", options->lcm_network,
                "Allow an LCM URL that other hosts reach (see `rigcal calib --help`)");
  cmd->add_flag("--once", options->once,
                "Wait for one RIGCAL_STATUS and one RIGCAL_EXTRINSICS (at most --timeout), print "
                "the snapshot and exit with the health code");
  cmd->add_flag("--json", options->json,
                "Print JSON instead of text (--once: one object; else one object per line)");
  cmd->add_option("--timeout", options->timeout_s, "--once: seconds to wait for the messages")
      ->check(CLI::PositiveNumber)
      ->default_val(5.0);
  cmd->add_option("--refresh", options->refresh_s, "Seconds between dashboard refreshes")
      ->check(CLI::PositiveNumber)
      ->default_val(1.0);
  cmd->callback([options, exit_code]() {
    monitor::StatusRunOptions run = *options;
    run.ansi = !run.once && !run.json && isatty(STDOUT_FILENO) == 1;
    run.width = run.ansi ? TerminalWidth() : 0;
    StopSignal stop_signal;
    *exit_code = monitor::RunStatusMonitor(run, std::cout, std::cerr, stop_signal.flag());
  });
}

}  // namespace rigcal::cli
