// SPDX-License-Identifier: Apache-2.0
// `rigcal experiment stability|poses|motion-model|scale-model|all`: the thesis chapter 5.1-5.3
// experiments (figures 5.1-5.6) with CSV, SVG figures and a printed summary.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "command_line.h"
#include "commands.h"
#include "rigcal/base/logging.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/research/experiments.h"
#include "rigcal/research/pair_evaluation.h"

namespace rigcal::cli {
namespace {

struct ExperimentArgs {
  std::string name;
  int samples = 200;
  uint64_t seed = 1;
  int threads = 2;
  int crb_samples = 200;
  int partitions = 0;
  std::string out_dir = "experiments";
  // pairs
  std::string data_dir;
  std::string only;
  int repeats = 3;
  bool no_online = false;
  int history_sets = -1;  // pairs: the online estimator's pose history; -1 = its default
  bool held_out = false;  // pairs: the held-out rigs (HeldOutPairScenarios) instead
};

// Progress on stderr at every 10 % of the work, once the run has taken more than 2 s.
research::ExperimentProgress StderrProgress(const std::string& name, bool quiet) {
  if (quiet) return nullptr;
  const auto start = std::chrono::steady_clock::now();
  return [name, start](int64_t done, int64_t total) {
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (elapsed < 2.0) return;
    const double fraction = static_cast<double>(done) / static_cast<double>(total);
    const double remaining = fraction > 0 ? elapsed * (1.0 - fraction) / fraction : 0.0;
    std::fprintf(stderr,
                 "rigcal experiment %s: %3.0f %% (%lld/%lld samples), %.1f s, ~%.0f s left\n",
                 name.c_str(), 100.0 * fraction, static_cast<long long>(done),
                 static_cast<long long>(total), elapsed, remaining);
  };
}

// `rigcal experiment pairs`: the pair-policy evaluation (pair_evaluation.h).
int RunPairs(const ExperimentArgs& args) {
  // Hundreds of solves and replays: their per-slave log lines would drown the table.
  ModuleLogger("calib")->set_level(spdlog::level::err);
  std::vector<std::string> notes;
  const std::vector<research::PairScenario> scenarios =
      args.held_out ? research::HeldOutPairScenarios(args.data_dir, &notes)
                    : research::PairScenarios(args.data_dir, &notes);
  for (const auto& note : notes) std::cerr << "rigcal experiment pairs: " << note << "\n";
  research::PairEvaluationOptions options;
  options.repeats = args.repeats;
  options.seed = args.seed;
  options.threads = args.threads;
  options.online = !args.no_online;
  options.online_history_sets = args.history_sets;
  options.only = args.only;
  options.progress = StderrProgress("pairs", QuietRequested());
  const auto start = std::chrono::steady_clock::now();
  const auto results = research::RunPairEvaluation(scenarios, options);
  if (results.empty()) {
    std::cerr << "rigcal experiment pairs: no scenario matches --only '" << args.only << "'\n";
    return 2;
  }
  const std::string table = research::FormatPairTable(results);
  std::cout << table;
  std::error_code ec;
  std::filesystem::create_directories(args.out_dir, ec);
  const std::string csv = args.out_dir + "/pairs.csv";
  const std::string txt = args.out_dir + "/pairs_summary.txt";
  for (const auto& [path, text] :
       {std::pair{csv, research::PairCsv(results)}, std::pair{txt, table}}) {
    if (const Status written = io::WriteFileAtomically(path, text); !written.ok()) {
      std::cerr << "rigcal experiment pairs: " << written.message() << "\n";
      return 1;
    }
  }
  std::printf("finished in %.1f s; wrote %s %s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(),
              csv.c_str(), txt.c_str());
  return 0;
}

int Run(const ExperimentArgs& args) {
  if (args.name == "pairs") return RunPairs(args);
  std::vector<research::ExperimentKind> kinds;
  if (args.name == "all") {
    kinds = {research::ExperimentKind::kStability, research::ExperimentKind::kPoses,
             research::ExperimentKind::kMotionModel, research::ExperimentKind::kScaleModel};
  } else {
    research::ExperimentKind kind;
    if (!research::ParseExperimentKind(args.name, &kind)) {
      std::cerr << "rigcal experiment: unknown experiment '" << args.name << "'\n";
      return 2;
    }
    kinds = {kind};
  }
  research::ExperimentOptions options;
  options.samples = args.samples;
  options.seed = args.seed;
  options.threads = args.threads;
  options.crb_samples = args.crb_samples;
  options.partitions = args.partitions;
  if (const Status status = options.Check(); !status.ok()) {
    std::cerr << "rigcal experiment: invalid options: " << status.message() << "\n";
    return 2;
  }
  for (research::ExperimentKind kind : kinds) {
    options.progress = StderrProgress(ToString(kind), QuietRequested());
    const auto start = std::chrono::steady_clock::now();
    const research::ExperimentResult result = research::RunExperiment(kind, options);
    if (!result.error.empty()) {
      std::cerr << "rigcal experiment " << ToString(kind) << ": " << result.error << "\n";
      return 2;
    }
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::cout << research::FormatSummary(result);
    const auto written = research::WriteExperimentOutputs(result, args.out_dir);
    if (!written.ok()) {
      std::cerr << "rigcal experiment " << ToString(kind) << ": " << written.error() << "\n";
      return 1;
    }
    std::printf("finished in %.1f s; wrote", seconds);
    for (const std::string& path : *written) std::cout << " " << path;
    std::cout << "\n\n";
  }
  return 0;
}

}  // namespace

void RegisterExperiment(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<ExperimentArgs>();
  CLI::App* cmd = app.add_subcommand(
      "experiment",
      "Thesis chapter 5.1-5.3 synthetic experiments (figures 5.1-5.6):\n"
      "  stability     errors of LLS and NL over the pose orientation error 0..3 deg (5.1, 5.2)\n"
      "  poses         errors of LLS and NL over the number of poses 4..24 (5.3, 5.4)\n"
      "  motion-model  general vs purely translational motion model (5.5)\n"
      "  scale-model   time-fixed vs time-dependent scale model (5.6)\n"
      "  all           the four in turn\n"
      "  pairs         the default pair policy against every fixed span relative:N, and the\n"
      "                online estimator against the batch solve, on simulated drives and\n"
      "                (with --data DIR) the real KITTI 00 and EuRoC V1_02 trajectories\n"
      "Writes <name>.csv, <name>_summary.txt and fig5_*.svg into --out-dir and prints the\n"
      "summary, with the Cramer-Rao bound next to the errors of stability and poses.");
  cmd->add_option("name", args->name, "stability, poses, motion-model, scale-model, all or pairs")
      ->required()
      ->check(CLI::IsMember({"stability", "poses", "motion-model", "scale-model", "all", "pairs"}));
  cmd->add_option("--data", args->data_dir,
                  "pairs: directory with KITTI_00_gt.txt, KITTI_00_gt_times.txt and\n"
                  "V102_groundtruth.csv (without it: simulated drives only)");
  cmd->add_option("--only", args->only, "pairs: the scenarios whose name contains this");
  cmd->add_option("--repeats", args->repeats, "pairs: noise draws per scenario")
      ->default_val(3)
      ->check(CLI::Range(1, 1000));
  cmd->add_flag("--no-online", args->no_online, "pairs: skip the online estimator");
  cmd->add_option("--history-sets", args->history_sets,
                  "pairs: the online estimator's pose history (sets per slave; default 10000): "
                  "fewer than a drive's sets make it merge its history into group means as on a longer drive")
      ->check(CLI::Range(0, 100000000));
  cmd->add_flag("--held-out", args->held_out,
                "pairs: the held-out rigs (a four-camera layout, scales 0.1-4, 5-50 Hz, 40-600 s)\n"
                "instead of the evaluation set");
  cmd->add_option("--samples", args->samples,
                  "random problem instances per grid point (the thesis used 100000)")
      ->default_val(200)
      ->check(CLI::Range(1, 100000000));
  cmd->add_option("--seed", args->seed, "random seed; results do not depend on --threads")
      ->default_val(1);
  cmd->add_option("--threads", args->threads, "worker threads (0 = all cores)")
      ->default_val(2)
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--crb-samples", args->crb_samples,
                  "geometries averaged for the Cramer-Rao bound (0 = no bound)")
      ->default_val(200)
      ->check(CLI::Range(0, 100000000));
  cmd->add_option("--partitions", args->partitions,
                  "scale-model: scales of the time-dependent model (0 = one per pose)")
      ->default_val(0)
      ->check(CLI::Range(0, 1000));
  cmd->add_option("-o,--out-dir", args->out_dir, "output directory (created if missing)")
      ->default_val("experiments");
  cmd->callback([args, exit_code]() { *exit_code = Run(*args); });
}

}  // namespace rigcal::cli
