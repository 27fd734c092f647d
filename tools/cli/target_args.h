// SPDX-License-Identifier: Apache-2.0
#pragma once
// Options shared by the target subcommands (`rigcal intrinsics`, `rigcal reference-compare`):
// cameras given as NAME=SOURCE, the chessboard, the resolution of AprilGrid detections, the
// camera model; and the step both run first, every camera's views and intrinsics.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/pattern/charuco.h"
#include "rigcal/pattern/intrinsics.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::cli {

struct TargetArgs {
  std::vector<std::string> cameras;  // NAME=SOURCE
  std::string chessboard = "9x6";
  std::string charuco;  // SQUARESxSQUARES: images hold a ChArUco board instead of a chessboard
  double marker = 0.0;  // ChArUco marker edge (0: 0.7 of --square)
  std::string dictionary = pattern::CharucoSpec{}.dictionary;
  double square = 1.0;
  std::string resolution;  // WIDTHxHEIGHT, for detection CSVs
  std::string model = "pinhole";
  int max_views = pattern::IntrinsicsOptions{}.max_views;
  bool no_reject = false;
};

// Adds --camera, --chessboard, --charuco, --marker, --dictionary, --square, --resolution,
// --model, --max-views, --no-reject.
void AddTargetOptions(CLI::App* cmd, TargetArgs* args);

struct CameraCalibration {
  pattern::CameraViews views;
  pattern::IntrinsicsResult intrinsics;
};

// For every --camera: its views and intrinsics (logs a line per camera). Errors name the
// camera and the file.
Expected<std::vector<CameraCalibration>> CalibrateCameras(const TargetArgs& args);

}  // namespace rigcal::cli
