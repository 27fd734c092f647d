// SPDX-License-Identifier: Apache-2.0
// `rigcal demo`: pose-level calibration of the built-in simulated 3-camera rig.
#include <chrono>
#include <iostream>
#include <map>

#include "commands.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/result_json.h"

namespace rigcal::cli {
namespace {

struct DemoArgs {
  DriveOptions drive;
  bool json = false;
  std::string method = "nl";
};

int RunDemo(const DemoArgs& args) {
  const std::vector<std::string> names = {"front", "left", "back"};
  const SyntheticDrive drive = GenerateDrive(names, DemoRig(), args.drive);
  std::map<std::string, Similarity> truth;
  for (size_t i = 0; i < drive.truth.size(); ++i) truth[names[i + 1]] = drive.truth[i];

  CalibrationOptions options;
  options.method = args.method == "lls" ? Method::kLinear : Method::kNonlinear;
  const auto start = std::chrono::steady_clock::now();
  const RigCalibration result = CalibrateRig(drive.recording, options);
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  if (args.json) {
    std::cout << io::ResultToJson(result, &truth).dump(2) << "\n";
  } else {
    std::cout << "Simulated rig: master 'front', slaves 'left' (looking left, odometry unit x2) "
                 "and 'back' (looking backwards, odometry unit x0.5)\n"
              << drive.recording.size() << " synchronised poses per camera at "
              << args.drive.frame_rate_hz << " Hz, pose noise " << args.drive.rotation_noise_deg
              << " deg / " << args.drive.position_noise << " units, seed " << args.drive.seed
              << "\n"
              << result.pairs_selected << " time pairs, solved in " << ms << " ms\n\n"
              << io::FormatResultTable(result, &truth);
  }
  std::vector<SlaveState> states;
  for (const auto& s : result.slaves) states.push_back(s.state);
  return ExitCodeFor(states);
}

}  // namespace

void RegisterDemo(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<DemoArgs>();
  args->drive.num_frames = 1200;
  args->drive.rotation_noise_deg = 0.1;
  args->drive.position_noise = 0.003;
  args->drive.drift_deg_per_frame = 0.005;
  CLI::App* cmd = app.add_subcommand(
      "demo",
      "Calibrate the built-in simulated 3-camera rig (front master, left and back slaves with "
      "different odometry scales) from noisy per-camera poses and print the estimate next to "
      "the truth. Needs no data files.");
  cmd->add_option("--frames", args->drive.num_frames, "Synchronised poses per camera")
      ->default_val(args->drive.num_frames)
      ->check(CLI::Range(10, 10000000));
  cmd->add_option("--rate", args->drive.frame_rate_hz, "Frame rate, Hz")
      ->default_val(args->drive.frame_rate_hz)
      ->check(CLI::PositiveNumber);
  cmd->add_option("--noise-deg", args->drive.rotation_noise_deg,
                  "White rotation noise per pose, degrees")
      ->default_val(args->drive.rotation_noise_deg)
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--noise-pos", args->drive.position_noise,
                  "White position noise per pose, master units")
      ->default_val(args->drive.position_noise)
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--drift-deg", args->drive.drift_deg_per_frame,
                  "Random-walk rotation drift per frame, degrees")
      ->default_val(args->drive.drift_deg_per_frame)
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", args->drive.seed, "Random seed")->default_val(args->drive.seed);
  cmd->add_option("--method", args->method, "lls (linear only) or nl (with refinement)")
      ->default_val("nl")
      ->check(CLI::IsMember({"lls", "nl"}));
  cmd->add_flag("--json", args->json, "Print the result as JSON (schema of `rigcal solve`)");
  cmd->callback([args, exit_code]() { *exit_code = RunDemo(*args); });
}

}  // namespace rigcal::cli
