// SPDX-License-Identifier: Apache-2.0
// `rigcal report`: one self-contained HTML file of a calibration (its history, per-motion
// residua, camera health, the rig drawn, the final table).
#include <cmath>
#include <iostream>
#include <memory>
#include <string>

#include "commands.h"
#include "exit_codes.h"
#include "provenance_args.h"
#include "rigcal/base/logging.h"
#include "rigcal/report/report_html.h"
#include "rigcal/report/report_input.h"

namespace rigcal::cli {
namespace {

constexpr int kExitBadInput = 1;

struct ReportArgs {
  report::ReportOptions input;
  std::string out;
};

int RunReport(const ReportArgs& args) {
  auto data = report::LoadReport(args.input);
  if (!data) {
    std::cerr << "rigcal report: " << data.error() << "\n";
    return kExitBadInput;
  }
  const io::Provenance provenance =
      ProvenanceOf({args.input.input, args.input.poses_log, args.input.truth}, args.input.config,
                   std::isfinite(data->metres_per_unit) && data->metres_per_unit == 1.0);
  data->provenance.push_back("rigcal " + provenance.rigcal_version + ", " + provenance.date_utc);
  data->provenance.push_back("command: " + provenance.command);
  for (const io::InputFile& f : provenance.inputs) {
    data->provenance.push_back("input: " + f.path + " (" + std::to_string(f.bytes) +
                               " bytes, FNV-1a 64 " + f.fnv1a64 + ")");
  }
  if (Status written = report::WriteReportHtml(args.out, *data); !written.ok()) {
    std::cerr << "rigcal report: " << written.message() << "\n";
    return kExitBadInput;
  }
  auto log = ModuleLogger("tools");
  for (const std::string& note : data->notes) log->info("{}", note);
  std::cout << "report written to " << args.out << "\n";
  return kExitOk;
}

}  // namespace

void RegisterReport(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<ReportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "report",
      "One self-contained HTML file (inline SVG, no external files) of a calibration: the final\n"
      "table in the thesis's error-model columns, the rig from the top and the side with camera\n"
      "frusta, every parameter over time with +-sigma bands and the truth, the measured scales\n"
      "per motion with the rejection threshold (thesis fig. 5.12), the constraint residua over\n"
      "time (fig. 5.11) and their histograms with their sigma, the baselines |C| +- sigma (in\n"
      "metres when the unit is known: a metric master or result, or a metric truth), the\n"
      "cameras' intrinsics (--config) and the cameras' VO health.\n"
      "INPUT is an LCM log holding the RIGCAL_EXTRINSICS / RIGCAL_STATUS history (e.g. written by\n"
      "`rigcal calib --log in.log --publish-lcm file:///tmp/out.log?mode=w`) or a result file\n"
      "(YAML of --out or JSON of --json: the table and the rig only). The per-motion plots need\n"
      "the poses: RIGCAL_POSE_<camera> events in INPUT or --poses LOG.\n"
      "Exit codes: 0 written, 1 bad input (unreadable or unknown input, no history, a truth\n"
      "without the slaves, the output not writable), 2 usage.");
  cmd->add_option("INPUT", args->input.input, "LCM log with the history, or a result YAML/JSON")
      ->required();
  cmd->add_option("-o,--out", args->out, "HTML file to write (atomically)")->required();
  cmd->add_option("--poses", args->input.poses_log,
                  "LCM log with RIGCAL_POSE_<camera> events (e.g. the input of `rigcal calib "
                  "--log`) for the per-motion residua and measured scales");
  cmd->add_option("--truth", args->input.truth,
                  "True mountings: a rig YAML, a rig config whose cameras carry `truth`, or the "
                  "directory of `rigcal run --truth-out` (with the poses: the master unit aligned "
                  "per master segment, as `run --eval`)");
  cmd->add_option("--config", args->input.config,
                  "Rig config: the intrinsics table, and C in metres when its master is metric");
  cmd->callback([args, exit_code]() { *exit_code = RunReport(*args); });
}

}  // namespace rigcal::cli
