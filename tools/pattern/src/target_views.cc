// SPDX-License-Identifier: Apache-2.0
// Reading target views: chessboard detection in images, AprilGrid detection CSVs.
#include "rigcal/pattern/target_views.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <vector>

#include "image_views.h"
#include "opencv.h"
#include "rigcal/base/logging.h"

namespace rigcal::pattern {
namespace {

namespace fs = std::filesystem;

// The half-size of the cornerSubPix window for a chessboard view: half the shortest distance
// between neighbouring corners of the grid (rows x cols, row-major), at most 11 px (OpenCV's usual
// 23 x 23 window) and at least 2. A window reaching the neighbouring corners pulls the refined
// corner towards them: with the fixed 11 px, corners of squares 15 px wide in the image moved 1.9
// px RMS (6.7 px at worst), of 12 px squares 7.6 px (target/chessboard_render).
int SubPixelHalfWindow(const std::vector<cv::Point2f>& corners, int cols, int rows) {
  const auto at = [&](int r, int c) -> const cv::Point2f& {
    return corners[static_cast<size_t>(r) * static_cast<size_t>(cols) + static_cast<size_t>(c)];
  };
  double shortest = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (c + 1 < cols) shortest = std::min(shortest, cv::norm(at(r, c + 1) - at(r, c)));
      if (r + 1 < rows) shortest = std::min(shortest, cv::norm(at(r + 1, c) - at(r, c)));
    }
  }
  return std::clamp(static_cast<int>(std::floor(shortest / 2.0)), 2, 11);
}

bool IsImageFile(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".bmp", ".pgm", ".ppm", ".tif", ".tiff"}) {
    if (ext == e) return true;
  }
  return false;
}

// '*' any run of characters, '?' one character.
bool Matches(const char* pattern, const char* text) {
  if (*pattern == '\0') return *text == '\0';
  if (*pattern == '*') {
    for (const char* t = text;; ++t) {
      if (Matches(pattern + 1, t)) return true;
      if (*t == '\0') return false;
    }
  }
  if (*text == '\0') return false;
  return (*pattern == '?' || *pattern == *text) && Matches(pattern + 1, text + 1);
}

// The digits of the stem as the pairing key (see the header); -1 when it has none.
int64_t FileKey(const fs::path& path) {
  std::string digits;
  for (char c : path.stem().string()) {
    if (std::isdigit(static_cast<unsigned char>(c)) != 0) digits += c;
  }
  if (digits.empty() || digits.size() > 19) return -1;
  errno = 0;
  const long long value = std::strtoll(digits.c_str(), nullptr, 10);
  if (errno == ERANGE) return -1;
  if (value >= 1000000000000LL) return value;  // nanoseconds
  // A frame number (< 1e12) counts seconds; beyond what nanoseconds can hold it is no key.
  return value <= std::numeric_limits<int64_t>::max() / 1000000000LL ? value * 1000000000LL : -1;
}

// The files of `source`: a folder, or folder/pattern.
Expected<std::vector<fs::path>> ListFiles(const std::string& source,
                                          bool (*accept)(const fs::path&)) {
  fs::path folder = source;
  std::string pattern = "*";
  std::error_code ec;
  if (source.find_first_of("*?") != std::string::npos) {
    const fs::path parent = fs::path(source).parent_path();
    folder = parent.empty() ? fs::current_path(ec) : parent;
    pattern = fs::path(source).filename().string();
  }
  if (!fs::is_directory(folder, ec)) {
    return Error{"'" + folder.string() + "' is not a folder (expected a folder of images or " +
                 "detection CSVs, or folder/pattern)"};
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string name = entry.path().filename().string();
    if (Matches(pattern.c_str(), name.c_str()) && accept(entry.path())) {
      files.push_back(entry.path());
    }
  }
  if (ec) return Error{"cannot list '" + folder.string() + "': " + ec.message()};
  std::sort(files.begin(), files.end());
  return files;
}

void SortByKey(CameraViews* views) {
  std::stable_sort(views->views.begin(), views->views.end(),
                   [](const TargetView& a, const TargetView& b) { return a.t_ns < b.t_ns; });
}

}  // namespace

Status ChessboardSpec::Check() const {
  if (cols < 2 || rows < 2) {
    return Error{"chessboard: expected at least 2x2 inner corners, got " + std::to_string(cols) +
                 "x" + std::to_string(rows)};
  }
  if (!(square_size > 0.0)) return Error{"square size: must be > 0"};
  return {};
}

Status ParseChessboardSize(const std::string& text, ChessboardSpec* spec) {
  int cols = 0;
  int rows = 0;
  char x = 0;
  std::istringstream in(text);
  if (!(in >> cols >> x >> rows) || (x != 'x' && x != 'X') || !in.eof() || cols < 2 || rows < 2) {
    return Error{"expected COLSxROWS inner corners (e.g. 9x6), got '" + text + "'"};
  }
  spec->cols = cols;
  spec->rows = rows;
  return {};
}

bool IsDetectionFolder(const std::string& source) {
  auto csv = ListFiles(source, [](const fs::path& p) { return p.extension() == ".csv"; });
  return csv.ok() && !csv->empty();
}

Expected<CameraViews> internal::DetectImageViews(
    const std::string& camera, const std::string& source,
    const std::function<std::optional<TargetView>(const cv::Mat& grey)>& detect,
    const std::string& target_name, const std::string& hint, const ImageStream& images) {
  ImageStream stream = images;
  if (!stream) {
    // The folder's image files, one after the other.
    auto files = ListFiles(source, IsImageFile);
    if (!files) return Error{files.error()};
    if (files->empty()) return Error{source + ": no images (png, jpg, bmp, pgm, ppm, tif)"};
    stream = [files = std::move(*files),
              next = size_t{0}](GreyImage* out) mutable -> Expected<bool> {
      if (next == files.size()) return false;
      const fs::path& path = files[next++];
      const cv::Mat image = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
      if (image.empty()) return Error{path.string() + ": cannot read the image"};
      out->name = path.filename().string();
      out->t_ns = FileKey(path);
      out->width = image.cols;
      out->height = image.rows;
      out->pixels.resize(static_cast<size_t>(image.cols) * static_cast<size_t>(image.rows));
      for (int r = 0; r < image.rows; ++r) {
        std::copy(image.ptr<uint8_t>(r), image.ptr<uint8_t>(r) + image.cols,
                  out->pixels.begin() + static_cast<long>(r) * image.cols);
      }
      return true;
    };
  }
  const auto log = ModuleLogger("target");
  CameraViews out;
  out.camera = camera;
  std::string first_file;
  GreyImage grey;
  while (true) {
    Expected<bool> more = stream(&grey);
    if (!more) return Error{more.error()};
    if (!*more) break;
    if (grey.width <= 0 || grey.height <= 0 ||
        grey.pixels.size() != static_cast<size_t>(grey.width) * static_cast<size_t>(grey.height)) {
      return Error{source + ": " + grey.name + ": not a " + std::to_string(grey.width) + "x" +
                   std::to_string(grey.height) + " grey image"};
    }
    const cv::Mat image(grey.height, grey.width, CV_8UC1, grey.pixels.data());
    ++out.files;
    if (out.width == 0) {
      out.width = image.cols;
      out.height = image.rows;
      first_file = grey.name;
    } else if (image.cols != out.width || image.rows != out.height) {
      return Error{source + ": mixed resolutions: " + first_file + " is " +
                   std::to_string(out.width) + "x" + std::to_string(out.height) + ", " + grey.name +
                   " is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                   " (one camera, one image size)"};
    }
    std::optional<TargetView> view = detect(image);
    if (!view) {
      out.none.push_back(grey.name);
      log->debug("{}: {}: no {}", source, grey.name, target_name);
      continue;
    }
    view->file = grey.name;
    view->t_ns = grey.t_ns;
    out.views.push_back(std::move(*view));
  }
  if (out.files == 0) return Error{source + ": no images"};
  if (out.views.empty()) {
    return Error{source + ": no " + target_name + " found in any of the " +
                 std::to_string(out.files) + " images; " + hint};
  }
  SortByKey(&out);
  return out;
}

Expected<CameraViews> DetectChessboardViews(const std::string& camera, const std::string& source,
                                            const ChessboardSpec& board,
                                            const ImageStream& images) {
  if (Status s = board.Check(); !s.ok()) return Error{s.message()};
  const cv::Size pattern(board.cols, board.rows);
  auto detect = [&](const cv::Mat& image) -> std::optional<TargetView> {
    std::vector<cv::Point2f> corners;
    const bool found = cv::findChessboardCorners(
        image, pattern, corners, cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    if (!found || corners.size() != static_cast<size_t>(board.cols * board.rows)) {
      return std::nullopt;
    }
    const int half_window = SubPixelHalfWindow(corners, board.cols, board.rows);
    cv::cornerSubPix(image, corners, cv::Size(half_window, half_window), cv::Size(-1, -1),
                     cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 30, 0.01));
    TargetView view;
    for (int r = 0; r < board.rows; ++r) {
      for (int c = 0; c < board.cols; ++c) {
        const cv::Point2f& p = corners[static_cast<size_t>(r * board.cols + c)];
        view.pixels.emplace_back(p.x, p.y);
        view.target_points.emplace_back(c * board.square_size, r * board.square_size, 0.0);
      }
    }
    return view;
  };
  return internal::DetectImageViews(
      camera, source, detect,
      std::to_string(board.cols) + "x" + std::to_string(board.rows) + " chessboard (inner corners)",
      "check --chessboard COLSxROWS", images);
}

Expected<CameraViews> ReadAprilGridViews(const std::string& camera, const std::string& folder,
                                         int width, int height, int min_corners) {
  if (width <= 0 || height <= 0) {
    return Error{folder + ": AprilGrid detections need the image resolution (WIDTHxHEIGHT)"};
  }
  auto files = ListFiles(folder, [](const fs::path& p) { return p.extension() == ".csv"; });
  if (!files) return Error{files.error()};
  if (files->empty()) return Error{folder + ": no <t_ns>.csv detection files"};
  CameraViews out;
  out.camera = camera;
  out.width = width;
  out.height = height;
  for (const fs::path& path : *files) {
    std::ifstream in(path);
    if (!in) return Error{path.string() + ": cannot open"};
    ++out.files;
    TargetView view;
    view.file = path.filename().string();
    view.t_ns = FileKey(path);
    if (view.t_ns < 0) return Error{path.string() + ": file name is not <t_ns>.csv"};
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      if (line.empty() || line[0] == '#') continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream fields(line);
      double v[12];
      for (double& x : v) {
        if (!(fields >> x)) {
          return Error{path.string() + ":" + std::to_string(line_no) +
                       ": expected 12 numbers: ts,tag_rows,tag_cols,tag_size,tag_spacing,kp_x,"
                       "kp_y,p_x,p_y,p_z,tag_id,corner_idx"};
        }
      }
      const double u = v[5];
      const double w = v[6];
      if (!(u >= -0.5 && u <= width - 0.5 && w >= -0.5 && w <= height - 0.5)) {
        return Error{path.string() + ":" + std::to_string(line_no) + ": kp_x, kp_y: corner (" +
                     std::to_string(u) + ", " + std::to_string(w) + ") outside the " +
                     std::to_string(width) + "x" + std::to_string(height) + " image"};
      }
      view.pixels.emplace_back(u, w);
      view.target_points.emplace_back(v[7], v[8], v[9]);
    }
    if (static_cast<int>(view.pixels.size()) < min_corners) {
      out.none.push_back(view.file);
      continue;
    }
    out.views.push_back(std::move(view));
  }
  if (out.views.empty()) {
    return Error{folder + ": no target found: none of the " + std::to_string(out.files) +
                 " detection files has " + std::to_string(min_corners) + " corners or more"};
  }
  SortByKey(&out);
  return out;
}

Expected<CameraViews> LoadCameraViews(const std::string& camera, const std::string& source,
                                      const ChessboardSpec& board, int width, int height) {
  if (IsDetectionFolder(source)) {
    if (width <= 0 || height <= 0) {
      return Error{source +
                   ": AprilGrid detection CSVs do not give the image size: give the "
                   "resolution (--resolution WIDTHxHEIGHT)"};
    }
    return ReadAprilGridViews(camera, source, width, height);
  }
  auto views = DetectChessboardViews(camera, source, board);
  if (!views) return views;
  if (width > 0 && height > 0 && (views->width != width || views->height != height)) {
    return Error{source + ": the images are " + std::to_string(views->width) + "x" +
                 std::to_string(views->height) + ", not the " + std::to_string(width) + "x" +
                 std::to_string(height) + " given"};
  }
  return views;
}

}  // namespace rigcal::pattern
