// SPDX-License-Identifier: Apache-2.0
// `rigcal synth-log`: writes the poses of a simulated drive of a configured rig as an LCM log,
// to try `rigcal calib` (replay it with `rigcal calib --log` or onto a bus with lcm-logplayer).
#include <iostream>
#include <map>
#include <memory>
#include <string>

#include "commands.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/lcm/pose_log.h"

namespace rigcal::cli {
namespace {

struct SynthLogArgs {
  std::string config;
  std::string out;
  std::string truth_out;
  std::string motion = "general";
  DriveOptions drive;
};

int RunSynthLog(const SynthLogArgs& args) {
  auto config = io::LoadRigConfig(args.config);
  if (!config) {
    std::cerr << "rigcal synth-log: " << config.error() << "\n";
    return 1;
  }
  std::vector<Similarity> rigs;
  std::map<std::string, Similarity> truth;
  for (size_t i = 1; i < config->cameras.size(); ++i) {
    const io::CameraConfig& camera = config->cameras[i];
    if (!camera.truth) {
      std::cerr << "rigcal synth-log: " << args.config << ": camera '" << camera.name
                << "' has no `truth` mounting to simulate\n";
      return 1;
    }
    rigs.push_back(*camera.truth);
    truth[camera.name] = *camera.truth;
  }
  DriveOptions drive = args.drive;
  if (args.motion == "planar") {
    drive.motion = DriveOptions::Motion::kPlanarYaw;
  } else if (args.motion == "translation") {
    drive.motion = DriveOptions::Motion::kTranslationOnly;
  }
  const SyntheticDrive sim = GenerateDrive(config->CameraNames(), rigs, drive);
  if (const Status status = lcm::WritePoseLog(args.out, sim.recording); !status.ok()) {
    std::cerr << "rigcal synth-log: " << status.message() << "\n";
    return 1;
  }
  if (!args.truth_out.empty()) {
    if (const Status status = io::WriteRigYaml(args.truth_out, truth); !status.ok()) {
      std::cerr << "rigcal synth-log: " << status.message() << "\n";
      return 1;
    }
  }
  std::cout << "wrote " << sim.recording.size() << " poses per camera of " << config->cameras.size()
            << " cameras to " << args.out << "\n";
  return 0;
}

}  // namespace

void RegisterSynthLog(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<SynthLogArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth-log",
      "Write the odometry poses of a simulated drive of the config's rig (cameras[].truth) as an\n"
      "LCM log of RIGCAL_POSE_<camera> events, to try `rigcal calib`.");
  cmd->add_option("--config", args->config, "Rig config YAML with `truth` for every slave")
      ->required();
  cmd->add_option("-o,--out", args->out, "LCM log file to write")->required();
  cmd->add_option("--truth-out", args->truth_out, "Also write the true rig as a rig YAML");
  cmd->add_option("--motion", args->motion, "general, planar (car-like yaw) or translation")
      ->check(CLI::IsMember({"general", "planar", "translation"}))
      ->default_val("general");
  cmd->add_option("--frames", args->drive.num_frames, "Poses per camera")
      ->check(CLI::Range(10, 10'000'000))
      ->default_val(1200);
  cmd->add_option("--rate", args->drive.frame_rate_hz, "Frame rate, Hz")
      ->check(CLI::Range(0.1, 10000.0))
      ->default_val(20.0);
  cmd->add_option("--noise-deg", args->drive.rotation_noise_deg, "Rotation noise per pose, deg")
      ->check(CLI::NonNegativeNumber)
      ->default_val(0.05);
  cmd->add_option("--noise-pos", args->drive.position_noise, "Position noise per pose, units")
      ->check(CLI::NonNegativeNumber)
      ->default_val(0.002);
  cmd->add_option("--segment-period", args->drive.segment_period_s,
                  "Seconds between odometry re-initialisations (new scale), 0 = never")
      ->check(CLI::NonNegativeNumber)
      ->default_val(0.0);
  cmd->add_option("--seed", args->drive.seed, "Random seed")->default_val(1);
  cmd->callback([args, exit_code]() { *exit_code = RunSynthLog(*args); });
}

}  // namespace rigcal::cli
