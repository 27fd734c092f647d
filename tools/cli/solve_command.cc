// SPDX-License-Identifier: Apache-2.0
// `rigcal solve`: batch calibration of a rig from per-camera trajectory files.
// The flow that reads, matches, solves and prints; the options are in solve_args.cc, the target
// and metric parts in solve_target.cc.
#include <algorithm>
#include <cmath>
#include <exception>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "camchain_args.h"
#include "commands.h"
#include "exit_codes.h"
#include "provenance_args.h"
#include "rigcal/base/logging.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/result_json.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/time_offset.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/io/truth_alignment.h"
#include "rigcal/pipeline/online_replay.h"
#include "solve_args.h"
#include "solve_target.h"
#include "truth_args.h"

namespace rigcal::cli {
namespace {

// The offsets of `slaves` from the rig config's estimator.time_offset (nullopt: auto): 0 for
// every slave when the config has none (synchronised stamps). Errors: the config's, or a slave
// that is not a camera of the rig.
Expected<std::vector<std::optional<double>>> TimeOffsetsFromConfig(
    const std::string& path, const std::vector<std::string>& slaves) {
  auto config = io::LoadRigConfig(path);
  if (!config) return Error{config.error()};
  const std::vector<std::string> names = config->CameraNames();
  const ClockOffsetOptions& clock = config->online.time_offset;
  std::vector<std::optional<double>> out(slaves.size(), 0.0);
  for (size_t i = 0; i < slaves.size(); ++i) {
    const auto it = std::find(names.begin() + 1, names.end(), slaves[i]);
    if (it == names.end()) {
      return Error{path + ": slave '" + slaves[i] + "' is not a slave camera of the rig config"};
    }
    const auto j = static_cast<size_t>(it - names.begin()) - 1;
    if (clock.enabled) out[i] = j < clock.given_s.size() ? clock.given_s[j] : std::nullopt;
  }
  return out;
}

// The calibration options of the command line. Errors name the flag.
Expected<CalibrationOptions> SolveOptionsOf(const SolveArgs& args) {
  CalibrationOptions options;
  options.method = args.method == "lls" ? Method::kLinear : Method::kNonlinear;
  options.motion_model = args.motion == "general"         ? MotionModel::kGeneral
                         : args.motion == "planar"        ? MotionModel::kPlanar
                         : args.motion == "translational" ? MotionModel::kTranslational
                                                          : MotionModel::kAuto;
  options.nominal_sigma = args.prior_sigma;
  options.covariance_time_blocks = args.time_blocks;
  if (std::string e = ApplyScale(args.scale, &options); !e.empty()) {
    return Error{"--scale: " + e};
  }
  if (args.pose_model != "global" && args.reference != "target") {
    return Error{"--pose-model " + args.pose_model + " needs --reference target"};
  }
  if (std::string e = ApplyPairs(args.pairs, &options.pairs); !e.empty()) {
    return Error{"--pairs: " + e};
  }
  if (const Status checked = options.Check(); !checked.ok()) {
    return Error{"invalid options: " + checked.message()};
  }
  return options;
}

// What the command reads: the trajectories and the truth.
struct SolveInput {
  TimedTrajectory master;
  std::vector<TimedTrajectory> slaves;
  TruthFiles truth;  // empty without --truth
};

Expected<SolveInput> ReadSolveInput(const SolveArgs& args, spdlog::logger& log) {
  io::TrajectoryReadOptions read_options;
  read_options.max_quaternion_norm_error = args.max_quaternion_norm_error;
  auto read = [&](const std::string& argument) {
    io::TrajectoryFormat format = io::TrajectoryFormat::kTum;
    auto trajectory = io::ReadNamedTrajectory(argument, read_options, &format);
    if (trajectory) {
      log.info("{}: {} poses ({} format), camera '{}'", io::ParseNamedTrajectoryPath(argument).path,
               trajectory->size(), ToString(format), trajectory->name);
    }
    return trajectory;
  };
  SolveInput input;
  auto master = read(args.master);
  if (!master) return Error{master.error()};
  input.master = std::move(*master);
  for (const std::string& path : args.slaves) {
    auto slave = read(path);
    if (!slave) return Error{slave.error()};
    input.slaves.push_back(std::move(*slave));
  }
  if (args.truth.empty()) return input;
  std::vector<std::string> cameras = {input.master.name};
  for (const auto& slave : input.slaves) cameras.push_back(slave.name);
  auto loaded = ReadTruthFiles(args.truth, cameras);
  if (!loaded) return Error{loaded.error()};
  input.truth = std::move(*loaded);
  for (const auto& slave : input.slaves) {
    if (input.truth.mountings.count(slave.name) == 0) {
      std::string known;
      for (const auto& [name, rig] : input.truth.mountings) {
        known += (known.empty() ? "" : ", ") + name;
      }
      return Error{args.truth + ": no entry for slave '" + slave.name +
                   "' (the file has: " + known + ")"};
    }
  }
  return input;
}

// --prior: the nominal mountings into options->nominal (a slave without one is warned of).
Status ReadPrior(const SolveArgs& args, const SolveInput& input, CalibrationOptions* options,
                 spdlog::logger& log) {
  if (args.prior.empty()) return Status::Ok();
  auto nominal = io::ReadNominalMountings(args.prior);
  if (!nominal) return Error{nominal.error()};
  for (const auto& slave : input.slaves) {
    if (nominal->count(slave.name) == 0) {
      log.warn(
          "{}: no nominal mounting for slave '{}': what its motion cannot determine is "
          "reported unknown",
          args.prior, slave.name);
    }
  }
  options->nominal = std::move(*nominal);
  return Status::Ok();
}

// What the solve produced.
struct SolveOutcome {
  RigCalibration result;
  std::vector<pipeline::ConvergencePoint> history;  // --online
  std::optional<ResultUnit> unit;                   // what the positions are in, when known
};

// The given offsets of the slaves: from --config's estimator.time_offset, or --time-offset.
Expected<std::vector<std::optional<double>>> GivenTimeOffsets(
    const SolveArgs& args, const std::vector<TimedTrajectory>& slaves, spdlog::logger& log) {
  std::vector<std::string> slave_names;
  for (const auto& slave : slaves) slave_names.push_back(slave.name);
  if (!args.config.empty() && !args.time_offset_given) {
    auto from_config = TimeOffsetsFromConfig(args.config, slave_names);
    if (!from_config) return Error{from_config.error()};
    log.info("time offsets from {} (estimator.time_offset)", args.config);
    return from_config;
  }
  std::string offset_error;
  auto given = ParseTimeOffsets(args.time_offset, slave_names, &offset_error);
  if (!offset_error.empty()) return Error{"--time-offset: " + offset_error};
  return given;
}

// The hand-eye calibration from the motions: the poses matched in time (at the slaves' clock
// offsets), then the batch calibrator or, with --online, the online estimator.
Expected<SolveOutcome> SolveFromMotion(const SolveArgs& args, const SolveInput& input,
                                       const CalibrationOptions& options, int64_t tolerance_ns,
                                       spdlog::logger& log) {
  TimeOffsetOptions offset_options;
  offset_options.search_window_s = args.time_offset_window_s;
  auto given_offsets = GivenTimeOffsets(args, input.slaves, log);
  if (!given_offsets) return Error{given_offsets.error()};
  auto matched = io::MatchWithTimeOffsets(input.master, input.slaves, *given_offsets, tolerance_ns,
                                          options, offset_options);
  if (!matched) return Error{matched.error()};
  const RigRecording* recording = &matched->recording;
  log.info("{} stamps matched in all {} cameras (tolerance {} ms)", recording->size(),
           input.slaves.size() + 1, args.tolerance_ms);
  SolveOutcome outcome;
  try {
    if (args.online) {
      pipeline::OnlineReplayOptions replay;
      replay.report_every_s = args.report_every_s;
      replay.estimator.nominal_sigma = options.nominal_sigma;
      for (const auto& slave : recording->slaves) {
        const auto it = options.nominal.find(slave.name);
        replay.estimator.nominal.push_back(
            it == options.nominal.end() ? std::nullopt : std::optional<Similarity>(it->second));
      }
      const pipeline::OnlineReplayResult online = pipeline::ReplayOnline(
          *recording, replay, args.truth.empty() ? nullptr : &input.truth.mountings);
      log.info("sync buffer: {}", online.sync.BriefReport());
      outcome.history = online.history;
      outcome.result = online.estimate.rig;
    } else {
      outcome.result = CalibrateRig(*recording, options);
      // The estimated offsets' σ in the extrinsics' and scales' σ.
      if (const Status propagated = io::PropagateTimeOffsetSigma(
              input.master, input.slaves, *matched, tolerance_ns, options, &outcome.result);
          !propagated.ok()) {
        return Error{propagated.message()};
      }
    }
  } catch (const std::exception& e) {
    return Error{std::string("calibration failed: ") + e.what()};
  }
  // Timing checked where the offsets were given (0 for synchronised cameras).
  for (const std::string& found : io::CheckGivenTimeOffsets(
           input.master, input.slaves, *given_offsets, offset_options, &outcome.result)) {
    log.warn("{}", found);
  }
  if (outcome.result.master.empty()) outcome.result.master = input.master.name;
  for (size_t i = 0; i < outcome.result.slaves.size() && i < matched->offsets.size(); ++i) {
    outcome.result.slaves[i].time_offset_s = matched->offsets[i].offset_s;
    outcome.result.slaves[i].time_offset_std_s = matched->offsets[i].std_s;
  }
  return outcome;
}

// --metric-target or --master-metric: the unit of the positions (printed above the result).
Status ApplyMetricUnit(const SolveArgs& args, const SolveInput& input, int64_t tolerance_ns,
                       SolveOutcome* outcome) {
  if (!args.metric_target.empty()) {
    auto applied =
        ApplyMetricTarget(args.metric_target, input.master, tolerance_ns, &outcome->result);
    if (!applied) return Error{applied.error()};
    outcome->unit = *applied;
  } else if (args.master_metric) {
    outcome->unit = ResultUnit{true, 1.0, 0.0, "master odometry",
                               "positions in metres: the master odometry is metric "
                               "(--master-metric), its scale fixed to 1; slave scales map slave "
                               "units to metres"};
  }
  if (outcome->unit) {
    std::ostream& stream = args.json ? std::cerr : std::cout;
    stream << "units: " << outcome->unit->message << "\n";
    if (outcome->unit->metric) stream << UnobservableHeightNote(outcome->result);
  }
  return Status::Ok();
}

// The truth in the estimate's unit (truth_args.h: per master segment with the true
// trajectories of a --truth-out directory, else fitted to the truth's C), also for the
// convergence history's errors.
struct AlignedTruth {
  std::optional<io::TruthAlignment> alignment;
  std::map<std::string, Similarity> in_master_units;
};

Expected<AlignedTruth> AlignSolveTruth(const SolveArgs& args, const SolveInput& input,
                                       SolveOutcome* outcome, spdlog::logger& log) {
  AlignedTruth aligned;
  if (args.truth.empty()) return aligned;
  io::TruthUnit unit = io::TruthUnit::kAuto;
  io::ParseTruthUnit(args.truth_unit, &unit);
  std::vector<TimedTrajectory> odometry = {input.master};
  odometry.insert(odometry.end(), input.slaves.begin(), input.slaves.end());
  auto comparison = CompareRunWithTruth(outcome->result, input.truth, unit, odometry);
  if (!comparison) return Error{"--truth: " + comparison.error()};
  aligned.alignment = comparison->alignment;
  aligned.in_master_units = comparison->truth_master_units;
  log.info("--truth: {}", aligned.alignment->message);
  for (pipeline::ConvergencePoint& p : outcome->history) {
    const auto it = aligned.in_master_units.find(p.slave);
    if (p.error && it != aligned.in_master_units.end()) {
      p.error = CompareToTruth(p.estimate, it->second);
    }
  }
  return aligned;
}

// C in metres: a metric unit applied (metric master, --metric-*) or a target reference.
bool MetricResult(const SolveOutcome& outcome) {
  return outcome.unit && (outcome.unit->metric || outcome.unit->source == "target reference");
}

io::Provenance SolveProvenance(const SolveArgs& args, const SolveOutcome& outcome) {
  std::vector<std::string> inputs = {io::ParseNamedTrajectoryPath(args.master).path};
  for (const std::string& slave : args.slaves) {
    inputs.push_back(io::ParseNamedTrajectoryPath(slave).path);
  }
  inputs.push_back(args.truth);
  inputs.push_back(args.prior);
  return ProvenanceOf(inputs, args.config, MetricResult(outcome));
}

// The convergence (--online), then the result as a table or JSON on stdout.
void PrintSolveResult(const SolveArgs& args, const SolveOutcome& outcome,
                      const AlignedTruth& truth) {
  const std::optional<io::TruthAlignment>& alignment = truth.alignment;
  if (args.online) {
    // Convergence goes to stderr with --json so stdout stays one JSON object.
    std::ostream& stream = args.json ? std::cerr : std::cout;
    if (alignment && alignment->applied) {
      stream << "convergence errors in master units, the truth aligned: " << alignment->message
             << "\n";
    }
    stream << pipeline::FormatConvergence(outcome.history) << "\n";
  }
  const std::map<std::string, Similarity>* truth_ptr =
      args.truth.empty() ? nullptr : &truth.in_master_units;
  const io::TruthAlignment* alignment_ptr = alignment ? &*alignment : nullptr;
  if (args.json) {
    nlohmann::json json = io::ResultToJson(outcome.result, truth_ptr, alignment_ptr);
    if (outcome.unit) json["unit"] = outcome.unit->ToJson();
    json["provenance"] = io::ProvenanceToJson(SolveProvenance(args, outcome));
    std::cout << json.dump(2) << "\n";
  } else {
    std::cout << io::FormatResultTable(outcome.result, truth_ptr, alignment_ptr);
  }
  std::cout.flush();
}

// --out and --camchain.
Status WriteSolveFiles(const SolveArgs& args, const SolveOutcome& outcome, spdlog::logger& log) {
  if (!args.out.empty()) {
    const std::string units = outcome.unit ? "# units: " + outcome.unit->message + "\n" : "";
    const Status s =
        io::WriteFileAtomically(args.out, units + io::ResultToYaml(outcome.result) +
                                              io::ProvenanceToYaml(SolveProvenance(args, outcome)));
    if (!s.ok()) return s;
    log.info("wrote result to {}", args.out);
  }
  if (!args.camchain.empty()) {
    std::map<std::string, camera::CameraSpec> intrinsics;
    if (!args.config.empty()) {
      auto config = io::LoadRigConfig(args.config);
      if (!config) return Error{config.error()};
      intrinsics = IntrinsicsOf(*config);
    }
    const bool metres = MetricResult(outcome);
    return WriteResultCamchain(args.camchain, outcome.result, intrinsics,
                               metres ? 1.0 : std::nan(""), metres ? outcome.unit->source : "",
                               log);
  }
  return Status::Ok();
}

// 0 every slave usable, else 3, with the reason of each unusable slave on stderr.
int SolveExitCode(const RigCalibration& result) {
  std::vector<SlaveState> states;
  for (const SlaveCalibration& slave : result.slaves) {
    states.push_back(slave.state);
    if (slave.usable()) continue;
    std::cerr << "rigcal solve: " << slave.name << ": " << ToString(slave.state) << " ("
              << ToString(slave.termination) << "): " << slave.message << "\n";
  }
  return ExitCodeFor(states);
}

int RunSolve(const SolveArgs& args) {
  const auto log = ModuleLogger("tools");
  auto options = SolveOptionsOf(args);
  if (!options) return PrintCommandError("solve", options.error());
  auto input = ReadSolveInput(args, *log);
  if (!input) return PrintCommandError("solve", input.error());
  if (Status s = ReadPrior(args, *input, &*options, *log); !s.ok()) {
    return PrintCommandError("solve", s.message());
  }
  const auto tolerance_ns = static_cast<int64_t>(std::llround(args.tolerance_ms * 1e6));
  Expected<SolveOutcome> outcome = Error{""};
  if (args.reference == "target") {
    // The poses are target poses (camera in the target frame): global reference pose model.
    auto reference = TargetReferenceResult(input->master, input->slaves, tolerance_ns,
                                           args.pose_model == "individual");
    if (!reference) return PrintCommandError("solve", reference.error());
    outcome = SolveOutcome{std::move(*reference),
                           {},
                           ResultUnit{false, 1.0, 0.0, "target reference",
                                      "target reference: positions in the target's unit (metres "
                                      "for a metric target), scale 1 by definition"}};
  } else {
    outcome = SolveFromMotion(args, *input, *options, tolerance_ns, *log);
    if (!outcome) return PrintCommandError("solve", outcome.error());
  }
  if (Status s = ApplyMetricUnit(args, *input, tolerance_ns, &*outcome); !s.ok()) {
    return PrintCommandError("solve", s.message());
  }
  const Expected<AlignedTruth> truth = AlignSolveTruth(args, *input, &*outcome, *log);
  if (!truth) return PrintCommandError("solve", truth.error());
  PrintSolveResult(args, *outcome, *truth);
  if (Status s = WriteSolveFiles(args, *outcome, *log); !s.ok()) {
    return PrintCommandError("solve", s.message());
  }
  return SolveExitCode(outcome->result);
}

}  // namespace

void RegisterSolve(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<SolveArgs>();
  CLI::App* cmd = app.add_subcommand(
      "solve",
      "Calibrate a rig from per-camera trajectory files: estimate every slave camera's\n"
      "orientation, position and odometry scale relative to the master camera.");

  AddSolveOptions(cmd, args.get());

  cmd->callback([args, exit_code, cmd]() {
    try {
      args->time_offset_given = cmd->count("--time-offset") > 0;
      *exit_code = RunSolve(*args);
    } catch (const std::exception& e) {
      *exit_code = PrintCommandError("solve", e.what());
    }
  });
}

}  // namespace rigcal::cli
