// SPDX-License-Identifier: Apache-2.0
#pragma once
// Subcommands of the rigcal command. Each Register* adds one subcommand to `app`; its
// callback stores the process exit code in *exit_code (0 every slave usable, 3 some slave not,
// 1 bad input; usage errors, 2, are CLI11's parse errors).

#include <CLI/CLI.hpp>

namespace rigcal::cli {

void RegisterSolve(CLI::App& app, int* exit_code);
void RegisterExperiment(CLI::App& app, int* exit_code);
void RegisterDemo(CLI::App& app, int* exit_code);
void RegisterCalib(CLI::App& app, int* exit_code);
void RegisterSynthLog(CLI::App& app, int* exit_code);
void RegisterRun(CLI::App& app, int* exit_code);
void RegisterStatus(CLI::App& app, int* exit_code);
void RegisterReport(CLI::App& app, int* exit_code);
void RegisterReplay(CLI::App& app, int* exit_code);
void RegisterRecord(CLI::App& app, int* exit_code);
void RegisterImport(CLI::App& app, int* exit_code);
void RegisterIntrinsics(CLI::App& app, int* exit_code);
void RegisterReferenceCompare(CLI::App& app, int* exit_code);
void RegisterTrigger(CLI::App& app, int* exit_code);
void RegisterVo(CLI::App& app, int* exit_code);
void RegisterDevices(CLI::App& app, int* exit_code);
void RegisterCheckConfig(CLI::App& app, int* exit_code);

}  // namespace rigcal::cli
