// SPDX-License-Identifier: Apache-2.0
// `rigcal import`: datasets into rigcal LCM logs. `import euroc DIR` writes the images of a EuRoC
// (ASL) recording as RIGCAL_IMAGE_<camera> events; `import tum NAME=FILE...` writes per-camera
// trajectories as RIGCAL_POSE_<camera> events. Both also write a rig config naming the cameras
// (with the intrinsics of sensor.yaml for EuRoC), for `rigcal calib --log` and replays.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/capture/image_folder_device.h"
#include "rigcal/io/camera_files.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/log_writer.h"
#include "rigcal/lcm/pose_log.h"
#include "rigcal/pipeline/capture_sources.h"
#include "rigcal/pipeline/image_codec.h"

namespace rigcal::cli {
namespace {

namespace fs = std::filesystem;

struct ImportArgs {
  std::string out;
  std::string config_out;
  bool force = false;  // accepted, no effect: outputs are always replaced (output_files.h)
  // euroc
  std::string dir;
  std::string image_encoding = "png";
  int jpeg_quality = 90;
  double split_mb = 0.0;
  // tum
  std::vector<std::string> trajectories;
};

// The rig config written beside the log: --config-out, else "<log>.yaml".
std::string ConfigPath(const ImportArgs& args) {
  return args.config_out.empty() ? args.out + ".yaml" : args.config_out;
}

// Camera names become LCM channels and YAML strings: letters, digits, '_', '-', '.'.
bool ValidCameraName(const std::string& name) {
  return !name.empty() && name.size() <= 40 && std::all_of(name.begin(), name.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '-' || c == '.';
  });
}

// The mav0 folder of a EuRoC recording given as the recording's folder or mav0 itself, and its
// camera folders camN (with data.csv), by N.
Expected<std::vector<fs::path>> EurocCameraFolders(const std::string& dir) {
  std::error_code ec;
  fs::path mav0 = fs::path(dir) / "mav0";
  if (!fs::is_directory(mav0, ec)) mav0 = dir;
  if (!fs::is_directory(mav0, ec)) return Error{dir + ": not a directory"};
  std::vector<std::pair<int, fs::path>> cameras;
  for (const fs::directory_entry& entry : fs::directory_iterator(mav0, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() < 4 || name.compare(0, 3, "cam") != 0 ||
        !std::all_of(name.begin() + 3, name.end(), [](char c) { return std::isdigit(c) != 0; }) ||
        !fs::is_regular_file(entry.path() / "data.csv", ec)) {
      continue;
    }
    cameras.emplace_back(std::stoi(name.substr(3)), entry.path());
  }
  if (ec) return Error{mav0.string() + ": cannot list: " + ec.message()};
  if (cameras.empty()) {
    return Error{mav0.string() + ": no camera folders (EuRoC ASL layout: mav0/camN/data.csv)"};
  }
  std::sort(cameras.begin(), cameras.end());
  std::vector<fs::path> folders;
  for (const auto& [index, folder] : cameras) folders.push_back(folder);
  return folders;
}

int RunImportEuroc(const ImportArgs& args) {
  auto folders = EurocCameraFolders(args.dir);
  if (!folders) return PrintCommandError("import", folders.error());
  const std::string config_path = ConfigPath(args);
  lcm::CameraNames names;
  std::vector<io::CameraConfig> cameras;
  std::vector<std::unique_ptr<capture::ImageFolderDevice>> devices;
  for (const fs::path& folder : *folders) {
    const std::string name = folder.filename().string();
    auto device =
        capture::ImageFolderDevice::Open(folder.string(), name, static_cast<int>(names.size()));
    if (!device) return PrintCommandError("import", folder.string() + ": " + device.error());
    io::CameraConfig camera;
    camera.name = name;
    const fs::path sensor = folder / "sensor.yaml";
    std::error_code ec;
    if (fs::exists(sensor, ec)) {
      auto spec = io::ReadEurocSensorYaml(sensor.string(), name);
      if (!spec) return PrintCommandError("import", spec.error());
      camera.spec = *spec;
    } else {
      std::cerr << "rigcal import: " << sensor.string()
                << ": missing; the rig config gets no intrinsics for camera '" << name << "'\n";
    }
    std::cerr << "rigcal import: camera '" << name << "': " << (*device)->size()
              << " images listed in " << folder.string() << "\n";
    names.push_back(name);
    cameras.push_back(std::move(camera));
    devices.push_back(std::move(*device));
  }

  pipeline::ImageEncodeOptions encode;
  encode.encoding = *pipeline::ParseImageEncoding(args.image_encoding);  // CLI-checked
  encode.jpeg_quality = args.jpeg_quality;
  lcm::LogWriterOptions log_options;
  log_options.atomic = true;
  log_options.overwrite = true;  // output_files.h
  log_options.split_bytes = static_cast<int64_t>(std::llround(args.split_mb * 1e6));
  auto log = lcm::LogWriter::Open(args.out, log_options);
  if (!log) return PrintCommandError("import", log.error());

  // Merge the cameras by time: always write the earliest pending frame (lower index on ties).
  std::vector<std::optional<capture::Frame>> pending(devices.size());
  const auto grab = [&](size_t i) -> Status {
    auto frame = devices[i]->Grab();
    if (!frame) return frame.status();
    pending[i] = std::move(*frame);
    return Status::Ok();
  };
  for (size_t i = 0; i < devices.size(); ++i) {
    if (Status status = grab(i); !status.ok()) return PrintCommandError("import", status.message());
  }
  std::vector<int64_t> frames(devices.size(), 0);
  while (true) {
    std::optional<size_t> next;
    for (size_t i = 0; i < pending.size(); ++i) {
      if (pending[i] && (!next || pending[i]->t_ns < pending[*next]->t_ns)) next = i;
    }
    if (!next) break;
    const auto camera = static_cast<int>(*next);
    auto bytes = pipeline::EncodeImageEvent(*pending[*next], names, camera, encode);
    if (!bytes) return PrintCommandError("import", bytes.error());
    if (Status status = (*log)->Write(lcm::ImageChannel(names[*next]), pending[*next]->t_ns / 1000,
                                      bytes->data(), bytes->size());
        !status.ok()) {
      return PrintCommandError("import", status.message());
    }
    ++frames[*next];
    if (Status status = grab(*next); !status.ok())
      return PrintCommandError("import", status.message());
  }
  if (Status status = (*log)->Close(); !status.ok())
    return PrintCommandError("import", status.message());

  std::vector<capture::ImageFolderDevice*> folder_devices;
  for (const auto& device : devices) folder_devices.push_back(device.get());
  pipeline::ReportFolderProblems(folder_devices, "rigcal import: ", std::cerr);
  const std::string comment = "Cameras of the EuRoC recording " + args.dir +
                              " (intrinsics from mav0/camN/sensor.yaml),\nwritten by rigcal "
                              "import euroc with the log " +
                              args.out;
  if (Status status =
          io::WriteRigConfig(config_path, fs::path(args.dir).filename().string(), cameras, comment);
      !status.ok()) {
    return PrintCommandError("import", status.message());
  }
  std::cout << "imported";
  for (size_t i = 0; i < names.size(); ++i) {
    std::cout << (i == 0 ? " " : ", ") << frames[i] << " frames of " << names[i];
  }
  std::cout << " (" << ToString(encode.encoding) << ", "
            << static_cast<double>((*log)->bytes()) / 1e6 << " MB) into";
  for (const std::string& file : (*log)->files()) std::cout << " " << file;
  std::cout << "\nrig config: " << config_path << "\n";
  return kExitOk;
}

int RunImportTum(const ImportArgs& args) {
  const std::string config_path = ConfigPath(args);
  lcm::CameraNames names;
  std::vector<io::CameraConfig> cameras;
  std::vector<CameraPose> poses;
  for (const std::string& argument : args.trajectories) {
    io::TrajectoryFormat format = io::TrajectoryFormat::kTum;
    auto trajectory = io::ReadNamedTrajectory(argument, {}, &format);
    if (!trajectory) return PrintCommandError("import", trajectory.error());
    if (!ValidCameraName(trajectory->name)) {
      return PrintCommandError("import",
                               argument + ": camera name '" + trajectory->name +
                                   "' (use NAME=FILE with letters, digits, '_', '-', '.')");
    }
    if (std::find(names.begin(), names.end(), trajectory->name) != names.end()) {
      return PrintCommandError("import", argument + ": a second camera named '" + trajectory->name +
                                             "' (name them with NAME=FILE)");
    }
    std::cerr << "rigcal import: " << argument << ": " << trajectory->size() << " poses ("
              << ToString(format) << "), camera '" << trajectory->name << "'"
              << (names.empty() ? " (master)" : "") << "\n";
    for (size_t k = 0; k < trajectory->size(); ++k) {
      CameraPose pose;
      pose.camera = static_cast<int>(names.size());
      pose.t_ns = trajectory->t_ns[k];
      pose.pose = trajectory->poses[k];
      pose.segment = k < trajectory->segment.size() ? trajectory->segment[k] : 0;
      poses.push_back(pose);
    }
    names.push_back(trajectory->name);
    io::CameraConfig camera;
    camera.name = trajectory->name;
    cameras.push_back(std::move(camera));
  }
  const size_t count = poses.size();
  if (Status status = lcm::WritePoseEvents(args.out, names, std::move(poses)); !status.ok()) {
    return PrintCommandError("import", status.message());
  }
  if (Status status = io::WriteRigConfig(
          config_path, fs::path(args.out).stem().string(), cameras,
          "Cameras of the pose log " + args.out + " (master first), written by rigcal import tum");
      !status.ok()) {
    return PrintCommandError("import", status.message());
  }
  std::cout << "imported " << count << " poses of " << names.size() << " cameras into " << args.out
            << "\nrig config: " << config_path << "\n";
  return kExitOk;
}

void AddOutputOptions(CLI::App* cmd, ImportArgs* args) {
  cmd->add_option("-o,--out", args->out, "LCM log file to write (atomically)")->required();
  cmd->add_option("--config-out", args->config_out,
                  "Rig config written with the log (cameras, master first); default OUT.yaml");
  cmd->add_flag("-f,--force", args->force,
                "Accepted for older scripts: existing output files are always replaced (below)");
}

}  // namespace

void RegisterImport(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<ImportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "import",
      "Convert a dataset into a rigcal LCM log (lcm-logger format) and a rig config naming its\n"
      "cameras: `rigcal calib --log OUT --config OUT.yaml` replays a pose log.");
  cmd->require_subcommand(1);
  cmd->footer(
      "Exit status: 0 imported; 1 bad input or output error (the message names the file); "
      "2 usage.");

  CLI::App* euroc = cmd->add_subcommand(
      "euroc",
      "Images of a EuRoC / ASL recording (DIR/mav0/camN/data.csv + data/*.png, cam0 = master)\n"
      "as RIGCAL_IMAGE_<camN> events in time order; intrinsics from mav0/camN/sensor.yaml into\n"
      "the rig config. Listed images that are missing or unreadable are skipped and reported.");
  euroc->add_option("DIR", args->dir, "The recording's folder (holding mav0/) or mav0 itself")
      ->required();
  AddOutputOptions(euroc, args.get());
  euroc
      ->add_option("--image-encoding", args->image_encoding,
                   "raw, png (lossless, as EuRoC ships them) or jpeg")
      ->check(CLI::IsMember({"raw", "png", "jpeg"}))
      ->capture_default_str();
  euroc->add_option("--jpeg-quality", args->jpeg_quality, "JPEG quality, 1..100")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  euroc
      ->add_option("--split-mb", args->split_mb,
                   "Split into files of at most this many MB: OUT.00, OUT.01, ... (0 = one file)")
      ->check(CLI::NonNegativeNumber);
  euroc->callback([args, exit_code]() { *exit_code = RunImportEuroc(*args); });

  CLI::App* tum = cmd->add_subcommand(
      "tum",
      "Per-camera trajectories (TUM, EuRoC CSV or rigcal native, detected as by rigcal solve) as\n"
      "RIGCAL_POSE_<NAME> events in time order; the first is the master. NAME=FILE names a\n"
      "camera (default: the file name's stem); a 9th column (scale segment) is carried.");
  tum->add_option("NAME=FILE", args->trajectories, "Trajectory files, master first")
      ->required()
      ->expected(2, -1);
  AddOutputOptions(tum, args.get());
  tum->callback([args, exit_code]() { *exit_code = RunImportTum(*args); });
}

}  // namespace rigcal::cli
