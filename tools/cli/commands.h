#pragma once
// Subcommands of the rigcal command. Each Register* adds one subcommand to `app`; its
// callback stores the process exit code in *exit_code (0 success, 1 failure, 2 usage).

#include <CLI/CLI.hpp>

namespace rigcal::cli {

void RegisterSolve(CLI::App& app, int* exit_code);
void RegisterExperiment(CLI::App& app, int* exit_code);
void RegisterDemo(CLI::App& app, int* exit_code);
void RegisterCalib(CLI::App& app, int* exit_code);
void RegisterSynthLog(CLI::App& app, int* exit_code);
void RegisterRun(CLI::App& app, int* exit_code);
void RegisterRecord(CLI::App& app, int* exit_code);
void RegisterImport(CLI::App& app, int* exit_code);

}  // namespace rigcal::cli
