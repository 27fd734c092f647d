// SPDX-License-Identifier: Apache-2.0
// Shared options and first step of the target subcommands.
#include "target_args.h"

#include <chrono>
#include <set>
#include <sstream>

#include "lcm_image_stream.h"
#include "rigcal/base/logging.h"
#include "rigcal/camera/camera_spec.h"

namespace rigcal::cli {
namespace {

Status ParseResolution(const std::string& text, int* width, int* height) {
  if (text.empty()) return {};
  std::istringstream in(text);
  char x = 0;
  if (!(in >> *width >> x >> *height) || (x != 'x' && x != 'X') || !in.eof() || *width <= 0 ||
      *height <= 0) {
    return Error{"--resolution: expected WIDTHxHEIGHT (e.g. 752x480), got '" + text + "'"};
  }
  return {};
}

}  // namespace

void AddTargetOptions(CLI::App* cmd, TargetArgs* args) {
  cmd->add_option("--camera", args->cameras,
                  "A camera and its target views: NAME=SOURCE, SOURCE a folder of images, a\n"
                  "folder/pattern ('data/left*.jpg'), or a folder of AprilGrid detection CSVs\n"
                  "(<t_ns>.csv, EuRoC/yac format: ts,tag_rows,tag_cols,tag_size,tag_spacing,\n"
                  "kp_x,kp_y,p_x,p_y,p_z,tag_id,corner_idx). Repeat per camera; the first is\n"
                  "cam0. Views of different cameras are paired by the digits of their file\n"
                  "names (left07.jpg with right07.jpg; EuRoC stamps). SOURCE may also be an\n"
                  "LCM log (`rigcal record`, `rigcal import euroc`): the camera's images on\n"
                  "RIGCAL_IMAGE_<NAME>, paired by their capture stamps.")
      ->type_name("NAME=SOURCE")
      ->required();
  cmd->add_option("--chessboard", args->chessboard,
                  "Images: the chessboard's inner corners, COLSxROWS")
      ->type_name("COLSxROWS")
      ->check(CLI::Validator(
          [](std::string& v) {
            pattern::ChessboardSpec b;
            const Status s = pattern::ParseChessboardSize(v, &b);
            return s.ok() ? std::string() : s.message();
          },
          "COLSxROWS"))
      ->capture_default_str();
  cmd->add_option("--charuco", args->charuco,
                  "Images: a ChArUco board (OpenCV aruco) instead of a chessboard, its squares\n"
                  "along x and y; views may show part of it")
      ->type_name("SQUARESxSQUARES")
      ->check(CLI::Validator(
          [](std::string& v) {
            pattern::CharucoSpec b;
            const Status s = pattern::ParseCharucoSquares(v, &b);
            return s.ok() ? std::string() : s.message();
          },
          "SQUARESxSQUARES"))
      ->excludes("--chessboard");
  cmd->add_option("--marker", args->marker,
                  "ChArUco: edge of one marker, in the unit of --square (default 0.7 of it)")
      ->type_name("SIZE")
      ->check(CLI::PositiveNumber)
      ->needs("--charuco");
  cmd->add_option("--dictionary", args->dictionary,
                  "ChArUco: OpenCV's marker dictionary (DICT_4X4_50 ... DICT_7X7_1000,\n"
                  "DICT_ARUCO_ORIGINAL, DICT_APRILTAG_16h5/25h9/36h10/36h11)")
      ->capture_default_str()
      ->needs("--charuco");
  cmd->add_option("--square", args->square,
                  "Images: edge of one chessboard square; the unit of every position written\n"
                  "(give metres for metric results). AprilGrid CSVs carry their own 3-D\n"
                  "corners (metres).")
      ->type_name("SIZE")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--resolution", args->resolution,
                  "Image size of AprilGrid detection CSVs (not in the files), WIDTHxHEIGHT")
      ->type_name("WxH");
  cmd->add_option("--model", args->model,
                  "pinhole: radial-tangential k1 k2 p1 p2 (OpenCV calibrateCamera, k3 = 0 as\n"
                  "Kalibr's radtan); fisheye: equidistant k1..k4 (cv::fisheye::calibrate);\n"
                  "scaramuzza: omnidirectional polynomial model (OCamCalib: linear start, then\n"
                  "Ceres over centre, affine part, degree-4 polynomial), for lenses beyond 180\n"
                  "degrees. Kalibr has no polynomial model: --camchain then holds Kalibr's omni\n"
                  "(unified) model fitted to the same views by cv::omnidir.")
      ->check(CLI::IsMember({"pinhole", "fisheye", "scaramuzza"}))
      ->capture_default_str();
  cmd->add_option("--max-views", args->max_views,
                  "At most this many views go into the solver, spread evenly over the\n"
                  "recording (statistics cover every view)")
      ->check(CLI::Range(4, 100000))
      ->capture_default_str();
  cmd->add_flag("--no-reject", args->no_reject,
                "Keep every view (no outlier rejection by per-view RMS)");
}

Expected<std::vector<CameraCalibration>> CalibrateCameras(const TargetArgs& args) {
  const auto log = ModuleLogger("tools");
  pattern::ChessboardSpec board;
  board.square_size = args.square;
  if (Status s = pattern::ParseChessboardSize(args.chessboard, &board); !s.ok()) {
    return Error{"--chessboard: " + s.message()};
  }
  pattern::CharucoSpec charuco;
  if (!args.charuco.empty()) {
    if (Status s = pattern::ParseCharucoSquares(args.charuco, &charuco); !s.ok()) {
      return Error{"--charuco: " + s.message()};
    }
    charuco.square_size = args.square;
    charuco.marker_size = args.marker > 0.0 ? args.marker : 0.7 * args.square;
    charuco.dictionary = args.dictionary;
    if (Status s = charuco.Check(); !s.ok()) return Error{"--charuco: " + s.message()};
  }
  int width = 0;
  int height = 0;
  if (Status s = ParseResolution(args.resolution, &width, &height); !s.ok()) {
    return Error{s.message()};
  }
  pattern::IntrinsicsOptions options;
  options.model = *camera::ModelFromName(args.model);
  options.max_views = args.max_views;
  options.reject_outliers = !args.no_reject;
  std::vector<CameraCalibration> out;
  std::set<std::string> names;
  for (const std::string& argument : args.cameras) {
    const size_t eq = argument.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == argument.size()) {
      return Error{"--camera: expected NAME=SOURCE, got '" + argument + "'"};
    }
    const std::string name = argument.substr(0, eq);
    if (!names.insert(name).second) return Error{"--camera: camera '" + name + "' given twice"};
    CameraCalibration camera;
    const std::string source = argument.substr(eq + 1);
    // An LCM image log: the camera's RIGCAL_IMAGE_<name> images through the same detectors.
    const bool from_log = IsLcmImageLog(source);
    const pattern::ImageStream images =
        from_log ? LcmImageStream(source, name) : pattern::ImageStream{};
    // Progress: detection and calibration take seconds per camera.
    const auto started = std::chrono::steady_clock::now();
    auto seconds = [&started] {
      return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    };
    log->info("{}: detecting the pattern in {} ...", name, source);
    auto views = !args.charuco.empty() && (from_log || !pattern::IsDetectionFolder(source))
                     ? pattern::DetectCharucoViews(name, source, charuco, images)
                 : from_log ? pattern::DetectChessboardViews(name, source, board, images)
                            : pattern::LoadCameraViews(name, source, board, width, height);
    if (!views) return Error{name + ": " + views.error()};
    camera.views = std::move(*views);
    log->info("{}: {} files, {} with a target ({}x{}) in {:.1f} s; calibrating ...", name,
              camera.views.files, camera.views.views.size(), camera.views.width,
              camera.views.height, seconds());
    auto intrinsics = pattern::CalibrateIntrinsics(camera.views, options);
    if (!intrinsics) return Error{intrinsics.error()};
    log->info("{}: calibrated in {:.1f} s", name, seconds());
    camera.intrinsics = std::move(*intrinsics);
    out.push_back(std::move(camera));
  }
  return out;
}

}  // namespace rigcal::cli
