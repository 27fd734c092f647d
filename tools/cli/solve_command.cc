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

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/base/logging.h"
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

namespace rigcal::cli {
namespace {

// The offsets of `slaves` from the rig config's estimator.time_offset (nullopt: auto): 0 for
// every slave when the config has none (synchronised stamps). Errors: the config's, or a slave
// that is not a camera of the rig.
Expected<std::vector<std::optional<double>>> TimeOffsetsFromConfig(
    const std::string& path, const std::vector<std::string>& slaves) {
  auto config = tools::LoadRigConfig(path);
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

int RunSolve(const SolveArgs& args) {
  const auto log = ModuleLogger("tools");

  CalibrationOptions options;
  options.method = args.method == "lls" ? Method::kLinear : Method::kNonlinear;
  options.motion_model = args.motion == "general"         ? MotionModel::kGeneral
                         : args.motion == "planar"        ? MotionModel::kPlanar
                         : args.motion == "translational" ? MotionModel::kTranslational
                                                          : MotionModel::kAuto;
  options.nominal_sigma = args.prior_sigma;
  options.covariance_time_blocks = args.time_blocks;
  if (std::string e = ApplyScale(args.scale, &options); !e.empty()) {
    return PrintCommandError("solve", "--scale: " + e);
  }
  if (args.pose_model != "global" && args.reference != "target") {
    return PrintCommandError("solve",
                             "--pose-model " + args.pose_model + " needs --reference target");
  }
  if (std::string e = ApplyPairs(args.pairs, &options.pairs); !e.empty()) {
    return PrintCommandError("solve", "--pairs: " + e);
  }
  if (const Status checked = options.Check(); !checked.ok()) {
    return PrintCommandError("solve", "invalid options: " + checked.message());
  }

  tools::TrajectoryReadOptions read_options;
  read_options.max_quaternion_norm_error = args.max_quaternion_norm_error;
  auto read = [&](const std::string& argument) {
    tools::TrajectoryFormat format = tools::TrajectoryFormat::kTum;
    auto trajectory = tools::ReadNamedTrajectory(argument, read_options, &format);
    if (trajectory) {
      log->info("{}: {} poses ({} format), camera '{}'",
                tools::ParseNamedTrajectoryPath(argument).path, trajectory->size(),
                tools::ToString(format), trajectory->name);
    }
    return trajectory;
  };
  auto master = read(args.master);
  if (!master) return PrintCommandError("solve", master.error());
  std::vector<tools::TimedTrajectory> slaves;
  for (const std::string& path : args.slaves) {
    auto slave = read(path);
    if (!slave) return PrintCommandError("solve", slave.error());
    slaves.push_back(std::move(*slave));
  }

  std::map<std::string, Similarity> truth;
  if (!args.truth.empty()) {
    auto loaded = tools::ReadRigYaml(args.truth);
    if (!loaded) return PrintCommandError("solve", loaded.error());
    truth = std::move(*loaded);
    for (const auto& slave : slaves) {
      if (truth.count(slave.name) == 0) {
        std::string known;
        for (const auto& [name, rig] : truth) known += (known.empty() ? "" : ", ") + name;
        return PrintCommandError("solve", args.truth + ": no entry for slave '" + slave.name +
                                              "' (the file has: " + known + ")");
      }
    }
  }

  if (!args.prior.empty()) {
    auto nominal = tools::ReadNominalMountings(args.prior);
    if (!nominal) return PrintCommandError("solve", nominal.error());
    for (const auto& slave : slaves) {
      if (nominal->count(slave.name) == 0) {
        log->warn(
            "{}: no nominal mounting for slave '{}': what its motion cannot determine is "
            "reported unknown",
            args.prior, slave.name);
      }
    }
    options.nominal = std::move(*nominal);
  }

  const auto tolerance_ns = static_cast<int64_t>(std::llround(args.tolerance_ms * 1e6));
  RigCalibration result;
  std::vector<tools::ConvergencePoint> history;
  std::optional<ResultUnit> unit;
  if (args.reference == "target") {
    // The poses are target poses (camera in the target frame): global reference pose model.
    auto reference =
        TargetReferenceResult(*master, slaves, tolerance_ns, args.pose_model == "individual");
    if (!reference) return PrintCommandError("solve", reference.error());
    result = std::move(*reference);
    unit = ResultUnit{false, 1.0, 0.0, "target reference",
                      "target reference: positions in the target's unit (metres for a metric "
                      "target), scale 1 by definition"};
  } else {
    tools::TimeOffsetOptions offset_options;
    offset_options.search_window_s = args.time_offset_window_s;
    std::vector<std::string> slave_names;
    for (const auto& slave : slaves) slave_names.push_back(slave.name);
    std::vector<std::optional<double>> given_offsets;
    if (!args.config.empty() && !args.time_offset_given) {
      auto from_config = TimeOffsetsFromConfig(args.config, slave_names);
      if (!from_config) return PrintCommandError("solve", from_config.error());
      given_offsets = std::move(*from_config);
      log->info("time offsets from {} (estimator.time_offset)", args.config);
    } else {
      std::string offset_error;
      given_offsets = ParseTimeOffsets(args.time_offset, slave_names, &offset_error);
      if (!offset_error.empty()) {
        return PrintCommandError("solve", "--time-offset: " + offset_error);
      }
    }
    auto matched = tools::MatchWithTimeOffsets(*master, slaves, given_offsets, tolerance_ns,
                                               options, offset_options);
    if (!matched) return PrintCommandError("solve", matched.error());
    const RigRecording* recording = &matched->recording;
    log->info("{} stamps matched in all {} cameras (tolerance {} ms)", recording->size(),
              slaves.size() + 1, args.tolerance_ms);

    const std::map<std::string, Similarity>* truth_for_replay =
        args.truth.empty() ? nullptr : &truth;
    try {
      if (args.online) {
        tools::OnlineReplayOptions replay;
        replay.report_every_s = args.report_every_s;
        replay.estimator.nominal_sigma = options.nominal_sigma;
        for (const auto& slave : recording->slaves) {
          const auto it = options.nominal.find(slave.name);
          replay.estimator.nominal.push_back(
              it == options.nominal.end() ? std::nullopt : std::optional<Similarity>(it->second));
        }
        const tools::OnlineReplayResult online =
            tools::ReplayOnline(*recording, replay, truth_for_replay);
        log->info("sync buffer: {}", online.sync.BriefReport());
        history = online.history;
        result = online.estimate.rig;
      } else {
        result = CalibrateRig(*recording, options);
      }
    } catch (const std::exception& e) {
      return PrintCommandError("solve", std::string("calibration failed: ") + e.what());
    }
    if (result.master.empty()) result.master = master->name;
    for (size_t i = 0; i < result.slaves.size() && i < matched->offsets.size(); ++i) {
      result.slaves[i].time_offset_s = matched->offsets[i].offset_s;
      result.slaves[i].time_offset_std_s = matched->offsets[i].std_s;
    }
  }
  if (!args.metric_target.empty()) {
    auto applied = ApplyMetricTarget(args.metric_target, *master, tolerance_ns, &result);
    if (!applied) return PrintCommandError("solve", applied.error());
    unit = *applied;
  } else if (args.master_metric) {
    unit = ResultUnit{true, 1.0, 0.0, "master odometry",
                      "positions in metres: the master odometry is metric (--master-metric), "
                      "its scale fixed to 1; slave scales map slave units to metres"};
  }
  if (unit) {
    (args.json ? std::cerr : std::cout) << "units: " << unit->message << "\n";
    if (unit->metric) (args.json ? std::cerr : std::cout) << UnobservableHeightNote(result);
  }

  // The truth in the estimate's unit (a metric truth against monocular odometry: the master
  // unit fitted to the truth's C), also for the convergence history's errors.
  std::optional<tools::TruthAlignment> alignment;
  std::map<std::string, Similarity> truth_master_units;
  if (!args.truth.empty()) {
    tools::TruthUnit unit = tools::TruthUnit::kAuto;
    tools::ParseTruthUnit(args.truth_unit, &unit);
    alignment = tools::AlignTruthUnit(result, truth, unit);
    truth_master_units = tools::TruthInMasterUnits(truth, *alignment);
    log->info("--truth: {}", alignment->message);
    for (tools::ConvergencePoint& p : history) {
      const auto it = truth_master_units.find(p.slave);
      if (p.error && it != truth_master_units.end()) {
        p.error = CompareToTruth(p.estimate, it->second);
      }
    }
  }
  if (args.online) {
    // Convergence goes to stderr with --json so stdout stays one JSON object.
    std::ostream& stream = args.json ? std::cerr : std::cout;
    if (alignment && alignment->applied) {
      stream << "convergence errors in master units, the truth aligned: " << alignment->message
             << "\n";
    }
    stream << tools::FormatConvergence(history) << "\n";
  }
  const std::map<std::string, Similarity>* truth_ptr =
      args.truth.empty() ? nullptr : &truth_master_units;
  const tools::TruthAlignment* alignment_ptr = alignment ? &*alignment : nullptr;
  if (args.json) {
    nlohmann::json json = tools::ResultToJson(result, truth_ptr, alignment_ptr);
    if (unit) json["unit"] = unit->ToJson();
    std::cout << json.dump(2) << "\n";
  } else {
    std::cout << tools::FormatResultTable(result, truth_ptr, alignment_ptr);
  }
  std::cout.flush();

  if (!args.out.empty()) {
    const Status s = unit
                         ? tools::WriteFileAtomically(args.out, "# units: " + unit->message + "\n" +
                                                                    tools::ResultToYaml(result))
                         : tools::WriteResultYaml(args.out, result);
    if (!s.ok()) return PrintCommandError("solve", s.message());
    log->info("wrote result to {}", args.out);
  }
  if (!args.camchain.empty()) {
    if (Status s = tools::WriteCamchain(args.camchain, result); !s.ok()) {
      return PrintCommandError("solve", s.message());
    }
    log->info("wrote camera chain to {}", args.camchain);
  }

  std::vector<SlaveState> states;
  for (const SlaveCalibration& slave : result.slaves) {
    states.push_back(slave.state);
    if (slave.usable()) continue;
    std::cerr << "rigcal solve: " << slave.name << ": " << ToString(slave.state) << " ("
              << ToString(slave.termination) << "): " << slave.message << "\n";
  }
  return ExitCodeFor(states);
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
