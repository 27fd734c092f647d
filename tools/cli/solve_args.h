// SPDX-License-Identifier: Apache-2.0
#pragma once
// The arguments of `rigcal solve` (solve_command.cc): their struct, the option table with each
// option's help text, and the parsers of the values that need more than CLI11's checks.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/io/time_offset.h"

namespace rigcal::cli {

struct SolveArgs {
  std::string master;
  std::vector<std::string> slaves;
  std::string method = "nl";
  std::string motion = "auto";
  std::string scale = "auto";
  std::string pairs = "gls";
  double tolerance_ms = 5.0;
  std::string time_offset = "0";
  bool time_offset_given = false;  // --time-offset on the command line (overrides --config)
  std::string config;              // rig config: estimator.time_offset
  double time_offset_window_s = TimeOffsetOptions{}.search_window_s;
  double max_quaternion_norm_error = 1e-3;  // io::TrajectoryReadOptions
  std::string truth;
  std::string truth_unit = "auto";
  std::string prior;
  double prior_sigma = 0.0;
  int time_blocks = CalibrationOptions{}.covariance_time_blocks;
  std::string out;
  std::string camchain;
  bool json = false;
  bool online = false;
  std::string reference = "motion";   // motion | target (solve_target.h)
  std::string pose_model = "global";  // with --reference target: global | individual
  std::string metric_target;          // master target poses: lambda_world
  bool master_metric = false;         // the master odometry is in metres
  double report_every_s = 10.0;
};

// --scale value -> options; returns an error text or "".
std::string ApplyScale(const std::string& text, CalibrationOptions* options);
// --pairs value -> options; returns an error text or "".
std::string ApplyPairs(const std::string& text, PairOptions* pairs);
// --time-offset: "auto" or SECONDS for every slave, or per slave "NAME=auto|SECONDS,..."
// (slaves not named: 0; nullopt: auto). `slaves` empty: the syntax only. Sets *error (naming
// the entry).
std::vector<std::optional<double>> ParseTimeOffsets(const std::string& text,
                                                    const std::vector<std::string>& slaves,
                                                    std::string* error);

// Adds every option of `rigcal solve` to `cmd`, bound to *args, and the help's footer.
void AddSolveOptions(CLI::App* cmd, SolveArgs* args);

}  // namespace rigcal::cli
