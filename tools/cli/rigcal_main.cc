// SPDX-License-Identifier: Apache-2.0
// The rigcal command: parses the command line and hands over to a subcommand.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <exception>
#include <iostream>
#include <string>
#include <vector>

#include "command_line.h"
#include "commands.h"
#include "output_files.h"
#include "progress_line.h"
#include "rigcal/base/logging.h"
#include "rigcal_version.h"  // generated: RIGCAL_VERSION

int main(int argc, char** argv) {
  CLI::App app{
      "rigcal - online extrinsic calibration of multi-camera rigs from per-camera odometry.\n"
      "Estimates every slave camera's rotation, position and odometry scale relative to a\n"
      "master camera (hand-eye calibration with scale)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("rigcal ") + RIGCAL_VERSION);
  // Verbosity is accepted anywhere on the line (command_line.h): main() takes it out of the
  // arguments before parsing; these options only document it in --help.
  std::string log_level = "info";
  app.add_option("--log-level", log_level,
                 "trace, debug, info, warn, error or off (anywhere on the line)")
      ->default_val("info")
      ->envname("RIGCAL_LOG_LEVEL");
  bool documented_only = false;
  app.add_flag("-q,--quiet", documented_only,
               "Warnings and errors only, no progress display (anywhere on the line)");
  app.add_flag("-v,--verbose", documented_only,
               "Debug messages (anywhere on the line; --log-level trace for more)");
  app.parse_complete_callback([&log_level]() {
    if (!rigcal::SetLogLevel(log_level)) {
      throw CLI::ValidationError("--log-level", "unknown level '" + log_level + "'");
    }
  });

  int exit_code = 0;
  rigcal::cli::RegisterSolve(app, &exit_code);
#if defined(RIGCAL_WITH_RESEARCH)
  rigcal::cli::RegisterExperiment(app, &exit_code);
#endif
  rigcal::cli::RegisterRun(app, &exit_code);
  rigcal::cli::RegisterCalib(app, &exit_code);
  rigcal::cli::RegisterReplay(app, &exit_code);
  rigcal::cli::RegisterSynthLog(app, &exit_code);
  rigcal::cli::RegisterDemo(app, &exit_code);
  rigcal::cli::RegisterStatus(app, &exit_code);
  rigcal::cli::RegisterReport(app, &exit_code);
  rigcal::cli::RegisterRecord(app, &exit_code);
  rigcal::cli::RegisterImport(app, &exit_code);
  rigcal::cli::RegisterIntrinsics(app, &exit_code);
  rigcal::cli::RegisterReferenceCompare(app, &exit_code);
  rigcal::cli::RegisterTrigger(app, &exit_code);
  rigcal::cli::RegisterVo(app, &exit_code);
  rigcal::cli::RegisterDevices(app, &exit_code);
  rigcal::cli::RegisterCheckConfig(app, &exit_code);
  rigcal::cli::DocumentOutputFiles(app);

  rigcal::cli::SetInvocation(RIGCAL_VERSION, argc, argv);
  // Every module logger writes above a progress line (progress_line.h).
  rigcal::cli::InstallProgressAwareLogging({"calib", "capture", "drivers", "sim", "target", "tools",
                                            "trigger", "vo", "pipeline", "io", "lcm", "monitor",
                                            "report", "research", "pattern", "plot", "camera"});
  std::vector<std::string> args(argv + 1, argv + argc);
  const rigcal::cli::Verbosity verbosity = rigcal::cli::ExtractVerbosity(&args);
  if (verbosity.log_level) args.insert(args.begin(), "--log-level=" + *verbosity.log_level);
  rigcal::cli::SetQuietRequested(verbosity.quiet);
  const bool help = std::find(args.begin(), args.end(), "--help") != args.end() ||
                    std::find(args.begin(), args.end(), "-h") != args.end();
  if (const std::string error = rigcal::cli::UnknownWordError(app, args); !error.empty() && !help) {
    std::cerr << error << "\n";
    return 2;
  }
  try {
    std::reverse(args.begin(), args.end());  // CLI11 takes the words last first
    app.parse(args);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every other parse error is a usage error (2).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "rigcal: error: " << e.what() << "\n";
    return 1;
  }
  return exit_code;
}
