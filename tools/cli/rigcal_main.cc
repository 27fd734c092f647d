// The rigcal command: parses the command line and hands over to a subcommand.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "commands.h"
#include "rigcal/base/logging.h"

namespace {

// The first word of the command line that is not an option (nor --log-level's value) when it
// names no subcommand, else null.
const char* UnknownSubcommand(const CLI::App& app, int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string word = argv[i];
    if (word == "--log-level") {
      ++i;
      continue;
    }
    if (word.empty() || word[0] == '-') continue;
    for (const CLI::App* sub : app.get_subcommands({})) {
      if (sub->check_name(word)) return nullptr;
    }
    return argv[i];
  }
  return nullptr;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "rigcal - online extrinsic calibration of multi-camera rigs from per-camera odometry.\n"
      "Estimates every slave camera's rotation, position and odometry scale relative to a\n"
      "master camera (hand-eye calibration with scale)."};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("rigcal ") + RIGCAL_VERSION);
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

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every other parse error is a usage error (2).
    if (const char* unknown = UnknownSubcommand(app, argc, argv)) {
      std::cerr << "rigcal: unknown subcommand '" << unknown << "' (rigcal --help lists them)\n";
      return 2;
    }
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const std::exception& e) {
    std::cerr << "rigcal: error: " << e.what() << "\n";
    return 1;
  }
  return exit_code;
}
