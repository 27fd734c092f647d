// The rigcal command: parses the command line and hands over to a subcommand.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "commands.h"
#include "rigcal/calib/logging.h"

int main(int argc, char** argv) {
  CLI::App app{
      "rigcal - online extrinsic calibration of multi-camera rigs from per-camera odometry.\n"
      "Estimates every slave camera's rotation, position and odometry scale relative to a\n"
      "master camera (hand-eye calibration with scale)."};
  app.require_subcommand(1);
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error or off")
      ->default_val("info")
      ->envname("RIGCAL_LOG_LEVEL");
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
  rigcal::cli::RegisterSynthLog(app, &exit_code);
  rigcal::cli::RegisterDemo(app, &exit_code);
  rigcal::cli::RegisterRecord(app, &exit_code);
  rigcal::cli::RegisterImport(app, &exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every other parse error is a usage error (2).
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "rigcal: error: " << e.what() << "\n";
    return 1;
  }
  return exit_code;
}
