// SPDX-License-Identifier: Apache-2.0
// `rigcal intrinsics`: camera intrinsics from target views, written as a rig config, a complete
// Kalibr camchain and per-camera target poses.
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/base/logging.h"
#include "rigcal/io/kalibr_camchain.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/trajectory_io.h"
#include "rigcal/pattern/omni_intrinsics.h"
#include "rigcal/pattern/reference_calibration.h"
#include "rigcal/pattern/target_poses.h"
#include "target_args.h"

namespace rigcal::cli {
namespace {

struct IntrinsicsArgs {
  TargetArgs target;
  std::string config_out;
  std::string camchain;
  std::string poses_out;
  int64_t tolerance_ns = 1000000;
  bool per_view = false;
  bool json = false;
};

nlohmann::json ToJson(const CameraCalibration& c) {
  const pattern::IntrinsicsResult& r = c.intrinsics;
  nlohmann::json views = nlohmann::json::array();
  for (const pattern::ViewStatistics& v : r.views) {
    views.push_back({{"file", v.file},
                     {"corners", v.corners},
                     {"rms_px", v.rms_px},
                     {"max_px", v.max_px},
                     {"used", v.used},
                     {"rejected", v.rejected}});
  }
  nlohmann::json out = {{"name", r.spec.name},
                        {"model", std::string(camera::ModelName(r.spec.model))},
                        {"resolution", {r.spec.width, r.spec.height}}};
  if (r.spec.model == camera::CameraSpec::Model::kScaramuzza) {
    out["poly"] = r.spec.poly;
    out["center"] = r.spec.center;
    out["affine"] = r.spec.affine;
  } else {
    out["intrinsics"] = r.spec.intrinsics;
    out["distortion"] = r.spec.distortion;
  }
  // sigma per parameter; null when unknown (the scaramuzza model, or undetermined parameters).
  nlohmann::json sigma = nullptr;
  if (!r.parameter_std.empty()) {
    sigma = nlohmann::json::object();
    for (size_t i = 0; i < r.parameter_std.size(); ++i) {
      sigma[r.parameter_names[i]] = r.parameter_std[i];
    }
  }
  out["parameter_std"] = sigma;
  out.update({{"rms_px", r.rms_px},
              {"rejection_threshold_px", r.rejection_threshold_px},
              {"views_used", r.views_used},
              {"views_rejected", r.views_rejected},
              {"files", c.views.files},
              {"files_without_target", c.views.none.size()},
              {"views", views}});
  return out;
}

// The camchain entries of the cameras and their extrinsics (JSON), with the first problem of
// each kind; the outputs that do not need the chain are written regardless.
struct Chain {
  std::vector<io::CamchainEntry> entries;
  nlohmann::json extrinsics = nlohmann::json::array();
  std::string chain_error;  // no extrinsics between two cameras
  std::string model_error;  // no Kalibr model for a camera
};

// Camera i's entry: its intrinsics (Kalibr's omni model for a scaramuzza camera when a camchain
// is asked for) and, after the first, its pose in camera 0's frame from the target reference.
void AddToChain(const IntrinsicsArgs& args, const std::vector<CameraCalibration>& cameras,
                const std::vector<TimedTrajectory>& poses, size_t i, Chain* chain) {
  io::CamchainEntry entry;
  entry.spec = cameras[i].intrinsics.spec;
  entry.translation_unit = "m";  // the target's unit: --square in metres
  if (entry.spec.model == camera::CameraSpec::Model::kScaramuzza && !args.camchain.empty()) {
    auto omni = pattern::CalibrateOmni(cameras[i].views, args.target.max_views);
    if (omni) {
      if (!args.json) std::cout << pattern::FormatOmni(*omni);
      entry = omni->ToCamchainEntry();
      entry.translation_unit = "m";
    } else if (chain->model_error.empty()) {
      chain->model_error = "Kalibr's omni model for " + entry.spec.name + ": " + omni.error();
    }
  }
  if (i > 0) {
    auto reference = pattern::EstimateGlobalReference(poses[0], poses[i], args.tolerance_ns);
    if (reference) {
      const Similarity& s = reference->master_from_slave;
      entry.cam0_from_cam = s;
      chain->extrinsics.push_back({{"camera", reference->slave},
                                   {"q_wxyz", {s.q.w(), s.q.x(), s.q.y(), s.q.z()}},
                                   {"C", {s.C.x(), s.C.y(), s.C.z()}},
                                   {"rot_std_deg", reference->rot_std_deg},
                                   {"instants", reference->instants}});
      if (!args.json) std::cout << pattern::FormatReference(*reference, "units");
    } else if (chain->chain_error.empty()) {
      chain->chain_error = reference.error();
    }
  }
  chain->entries.push_back(std::move(entry));
}

void PrintIntrinsics(const IntrinsicsArgs& args, const std::vector<CameraCalibration>& cameras,
                     const Chain& chain) {
  if (args.json) {
    nlohmann::json out = {{"cameras", nlohmann::json::array()}, {"extrinsics", chain.extrinsics}};
    for (const CameraCalibration& c : cameras) out["cameras"].push_back(ToJson(c));
    std::cout << out.dump(2) << "\n";
  } else {
    for (const CameraCalibration& c : cameras) {
      std::cout << pattern::FormatIntrinsics(c.intrinsics, args.per_view);
    }
  }
  std::cout.flush();
}

// --config-out and --poses-out.
Status WriteConfigAndPoses(const IntrinsicsArgs& args,
                           const std::vector<CameraCalibration>& cameras,
                           const std::vector<TimedTrajectory>& poses) {
  const auto log = ModuleLogger("tools");
  if (!args.config_out.empty()) {
    std::vector<io::CameraConfig> configs;
    for (const CameraCalibration& c : cameras) {
      io::CameraConfig config;
      config.name = c.intrinsics.spec.name;
      config.spec = c.intrinsics.spec;
      configs.push_back(std::move(config));
    }
    const Status s = io::WriteRigConfig(
        args.config_out, "calibrated", configs,
        "rig config written by rigcal intrinsics: intrinsics calibrated from target views");
    if (!s.ok()) return s;
    log->info("wrote the intrinsics into the rig config {}", args.config_out);
  }
  if (args.poses_out.empty()) return Status::Ok();
  std::error_code ec;
  std::filesystem::create_directories(args.poses_out, ec);
  if (ec) return Error{"--poses-out: cannot create '" + args.poses_out + "': " + ec.message()};
  for (const TimedTrajectory& t : poses) {
    const std::string path = args.poses_out + "/" + t.name + ".tum";
    if (Status s = io::WriteTrajectoryTum(path, t); !s.ok()) return s;
    log->info("{}: {} target poses written to {}", t.name, t.size(), path);
  }
  return Status::Ok();
}

// --camchain, last: its errors leave the other outputs written.
Status WriteChain(const IntrinsicsArgs& args, const Chain& chain) {
  if (args.camchain.empty()) return Status::Ok();
  if (!chain.model_error.empty()) return Error{"--camchain: " + chain.model_error};
  if (!chain.chain_error.empty()) {
    return Error{"--camchain: no extrinsics between the cameras: " + chain.chain_error};
  }
  const Status s = io::WriteKalibrCamchain(
      args.camchain, chain.entries,
      "Kalibr camchain written by rigcal intrinsics: intrinsics from target views (OpenCV);\n"
      "T_cn_cnm1 from the target poses (global reference model), in the target's unit (--square).");
  if (s.ok()) ModuleLogger("tools")->info("wrote the Kalibr camchain {}", args.camchain);
  return s;
}

int RunIntrinsics(const IntrinsicsArgs& args) {
  if (!args.config_out.empty() && args.target.cameras.size() < 2) {
    return PrintCommandError("intrinsics",
                             "--config-out: a rig config has at least two cameras; give every "
                             "camera of the rig with --camera (--json and --camchain hold one "
                             "camera's intrinsics)");
  }
  auto cameras = CalibrateCameras(args.target);
  if (!cameras) return PrintCommandError("intrinsics", cameras.error());
  // Per camera its kept target poses.
  std::vector<TimedTrajectory> poses;
  for (const CameraCalibration& c : *cameras) {
    poses.push_back(pattern::PosesAsTrajectory(c.views.camera, c.intrinsics.views,
                                               c.intrinsics.rejection_threshold_px));
  }
  Chain chain;
  for (size_t i = 0; i < cameras->size(); ++i) AddToChain(args, *cameras, poses, i, &chain);
  PrintIntrinsics(args, *cameras, chain);
  if (Status s = WriteConfigAndPoses(args, *cameras, poses); !s.ok()) {
    return PrintCommandError("intrinsics", s.message());
  }
  if (Status s = WriteChain(args, chain); !s.ok()) {
    return PrintCommandError("intrinsics", s.message());
  }
  return kExitOk;
}

}  // namespace

void RegisterIntrinsics(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<IntrinsicsArgs>();
  CLI::App* cmd = app.add_subcommand(
      "intrinsics",
      "Calibrate camera intrinsics from views of a chessboard (images) or an AprilGrid\n"
      "(detection CSVs): per-view reprojection statistics, outlier views rejected, the\n"
      "standard deviation of every parameter (pinhole, fisheye; `parameter_std` in --json).");
  AddTargetOptions(cmd, &args->target);
  cmd->add_option("--config-out", args->config_out,
                  "Write a rig config with every camera's intrinsics (model, resolution,\n"
                  "intrinsics, distortion) here (atomically)")
      ->type_name("FILE");
  cmd->add_option("--camchain", args->camchain,
                  "Write a complete Kalibr camchain here: camera_model, intrinsics,\n"
                  "distortion_model, distortion_coeffs, resolution, rostopic and, between\n"
                  "consecutive cameras, T_cn_cnm1 from the shared target views. A scaramuzza\n"
                  "camera is written as Kalibr's omni (unified) model fitted by cv::omnidir")
      ->type_name("FILE");
  cmd->add_option("--poses-out", args->poses_out,
                  "Write every camera's target poses (camera in the target frame, the target's\n"
                  "unit) as DIR/NAME.tum: the input of `rigcal solve --reference target` and\n"
                  "`--metric-target`")
      ->type_name("DIR");
  cmd->add_flag("--per-view", args->per_view, "Print the reprojection error of every view");
  cmd->add_flag("--json", args->json, "Print the result as one JSON object on stdout");
  cmd->footer(
      "Exit status: 0 calibrated; 1 bad input (no target in any image, mixed resolutions,\n"
      "too few views, unreadable files) or an output error.");
  cmd->callback([args, exit_code]() {
    try {
      *exit_code = RunIntrinsics(*args);
    } catch (const std::exception& e) {
      *exit_code = PrintCommandError("intrinsics", e.what());
    }
  });
}

}  // namespace rigcal::cli
