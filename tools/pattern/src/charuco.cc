// SPDX-License-Identifier: Apache-2.0
// ChArUco views: OpenCV contrib aruco's marker detection and corner interpolation.
#include "rigcal/pattern/charuco.h"

#include <array>
#include <sstream>
#include <utility>

#include "image_views.h"
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/aruco/charuco.hpp>
#pragma GCC diagnostic pop

namespace rigcal::pattern {
namespace {

struct NamedDictionary {
  const char* name;
  cv::aruco::PREDEFINED_DICTIONARY_NAME id;
  int markers;
};

constexpr std::array<NamedDictionary, 21> kDictionaries = {{
    {"DICT_4X4_50", cv::aruco::DICT_4X4_50, 50},
    {"DICT_4X4_100", cv::aruco::DICT_4X4_100, 100},
    {"DICT_4X4_250", cv::aruco::DICT_4X4_250, 250},
    {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000, 1000},
    {"DICT_5X5_50", cv::aruco::DICT_5X5_50, 50},
    {"DICT_5X5_100", cv::aruco::DICT_5X5_100, 100},
    {"DICT_5X5_250", cv::aruco::DICT_5X5_250, 250},
    {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000, 1000},
    {"DICT_6X6_50", cv::aruco::DICT_6X6_50, 50},
    {"DICT_6X6_100", cv::aruco::DICT_6X6_100, 100},
    {"DICT_6X6_250", cv::aruco::DICT_6X6_250, 250},
    {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000, 1000},
    {"DICT_7X7_50", cv::aruco::DICT_7X7_50, 50},
    {"DICT_7X7_100", cv::aruco::DICT_7X7_100, 100},
    {"DICT_7X7_250", cv::aruco::DICT_7X7_250, 250},
    {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000, 1000},
    {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL, 1024},
    {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5, 30},
    {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9, 35},
    {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10, 2320},
    {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11, 587},
}};

const NamedDictionary* FindDictionary(const std::string& name) {
  for (const NamedDictionary& d : kDictionaries) {
    if (name == d.name) return &d;
  }
  return nullptr;
}

cv::Ptr<cv::aruco::CharucoBoard> MakeBoard(const CharucoSpec& spec) {
  return cv::aruco::CharucoBoard::create(
      spec.squares_x, spec.squares_y, static_cast<float>(spec.square_size),
      static_cast<float>(spec.marker_size),
      cv::aruco::getPredefinedDictionary(FindDictionary(spec.dictionary)->id));
}

}  // namespace

Status CharucoSpec::Check() const {
  if (squares_x < 2 || squares_y < 2) {
    return Error{"squares: " + std::to_string(squares_x) + "x" + std::to_string(squares_y) +
                 ", need at least 2x2"};
  }
  if (!(square_size > 0.0)) return Error{"square_size: must be > 0"};
  if (!(marker_size > 0.0 && marker_size < square_size)) {
    return Error{"marker_size: must be > 0 and smaller than the square (" +
                 std::to_string(square_size) + ")"};
  }
  const NamedDictionary* d = FindDictionary(dictionary);
  if (d == nullptr) {
    std::string known;
    for (const NamedDictionary& k : kDictionaries)
      known += (known.empty() ? "" : ", ") + std::string(k.name);
    return Error{"dictionary: unknown '" + dictionary + "' (" + known + ")"};
  }
  const int white = squares_x * squares_y / 2;  // the squares that hold a marker
  if (white > d->markers) {
    return Error{"dictionary: " + dictionary + " has " + std::to_string(d->markers) +
                 " markers, the board needs " + std::to_string(white)};
  }
  if (min_corners < 4) return Error{"min_corners: must be >= 4"};
  return Status::Ok();
}

Status ParseCharucoSquares(const std::string& text, CharucoSpec* spec) {
  std::istringstream in(text);
  int x = 0, y = 0;
  char sep = 0;
  if (!(in >> x >> sep >> y) || (sep != 'x' && sep != 'X') || !in.eof() || x < 2 || y < 2) {
    return Error{"expected SQUARESxSQUARES with at least 2 each (e.g. 5x7), got '" + text + "'"};
  }
  spec->squares_x = x;
  spec->squares_y = y;
  return Status::Ok();
}

Expected<CameraViews> DetectCharucoViews(const std::string& camera, const std::string& source,
                                         const CharucoSpec& spec, const ImageStream& images) {
  if (Status s = spec.Check(); !s.ok()) return Error{"ChArUco board: " + s.message()};
  const cv::Ptr<cv::aruco::CharucoBoard> board = MakeBoard(spec);
  const cv::Ptr<cv::aruco::DetectorParameters> params = cv::aruco::DetectorParameters::create();
  // The markers' corners are not refined (OpenCV's default, CORNER_REFINE_NONE): they only start
  // the chessboard corners, which interpolateCornersCharuco refines itself. Refined with
  // cornerSubPix, a marker's corner can settle towards the chessboard corner beside it (half the
  // square less the marker away on the board), and that chessboard corner, started from it, then
  // settles towards the marker's: on rendered views, corners 4-7 px off in half of the view sets
  // (RMS 0.26-0.52 px, fx up to 1 % off), where unrefined markers give 0.06-0.08 px in every set.
  params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_NONE;
  auto detect = [&](const cv::Mat& image) -> std::optional<TargetView> {
    std::vector<std::vector<cv::Point2f>> markers;
    std::vector<int> marker_ids;
    cv::aruco::detectMarkers(image, board->dictionary, markers, marker_ids, params);
    if (marker_ids.empty()) return std::nullopt;
    std::vector<cv::Point2f> corners;
    std::vector<int> ids;
    cv::aruco::interpolateCornersCharuco(markers, marker_ids, image, board, corners, ids);
    if (static_cast<int>(ids.size()) < spec.min_corners) return std::nullopt;
    TargetView view;
    for (size_t i = 0; i < ids.size(); ++i) {
      const cv::Point3f& p = board->chessboardCorners.at(static_cast<size_t>(ids[i]));
      view.pixels.emplace_back(corners[i].x, corners[i].y);
      view.target_points.emplace_back(p.x, p.y, p.z);
    }
    return view;
  };
  return internal::DetectImageViews(
      camera, source, detect,
      std::to_string(spec.squares_x) + "x" + std::to_string(spec.squares_y) + " ChArUco board (" +
          spec.dictionary + ", at least " + std::to_string(spec.min_corners) + " corners)",
      "check --charuco SQUARESxSQUARES, --marker and --dictionary", images);
}

Status DrawCharucoBoard(const CharucoSpec& spec, int pixels_per_square, const std::string& path) {
  if (Status s = spec.Check(); !s.ok()) return Error{"ChArUco board: " + s.message()};
  if (pixels_per_square < 10) return Error{"pixels_per_square: must be >= 10"};
  cv::Mat image;
  MakeBoard(spec)->draw(
      cv::Size((spec.squares_x + 2) * pixels_per_square, (spec.squares_y + 2) * pixels_per_square),
      image, pixels_per_square, 1);
  if (!cv::imwrite(path, image)) return Error{"cannot write '" + path + "'"};
  return Status::Ok();
}

}  // namespace rigcal::pattern
