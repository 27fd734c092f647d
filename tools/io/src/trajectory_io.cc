#include "rigcal/io/trajectory_io.h"

#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "rigcal/calib/format.h"
#include "rigcal/calib/logging.h"
#include "rigcal/io/atomic_file.h"

namespace rigcal::tools {
namespace {

constexpr int kPoseColumns = 8;
// Deviations of |q| from 1 below this are print rounding of a unit quaternion (>= 9
// decimals) and are normalised without being counted in the warning.
constexpr double kSilentNormError = 1e-9;

constexpr std::array<const char*, 9> kTumColumns = {"t [s]", "tx", "ty", "tz",     "qx",
                                                    "qy",    "qz", "qw", "segment"};
constexpr std::array<const char*, 8> kEurocColumns = {
    "timestamp [ns]", "p_x", "p_y", "p_z", "q_w", "q_x", "q_y", "q_z"};
constexpr std::array<const char*, 9> kNativeColumns = {"t_ns", "qw", "qx", "qy",     "qz",
                                                       "Cx",   "Cy", "Cz", "segment"};

std::string_view Trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

std::vector<std::string_view> SplitWhitespace(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    if (i == s.size()) break;
    size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

std::vector<std::string_view> SplitComma(std::string_view s) {
  std::vector<std::string_view> out;
  size_t start = 0;
  while (true) {
    const size_t comma = s.find(',', start);
    out.push_back(Trim(s.substr(start, comma == std::string_view::npos ? s.npos : comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return out;
}

bool IsPlainInteger(std::string_view s) {
  if (!s.empty() && (s[0] == '-' || s[0] == '+')) s.remove_prefix(1);
  return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; });
}

template <typename Int>
std::optional<Int> ParseInteger(std::string_view s) {
  if (!s.empty() && s[0] == '+') s.remove_prefix(1);
  Int value{};
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) return std::nullopt;
  return value;
}

std::optional<double> ParseDouble(std::string_view s) {
  if (s.size() > 1 && s[0] == '+') s.remove_prefix(1);
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
  if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) return std::nullopt;
  return value;
}

// Parser of one data line; every error names path, line and column.
class LineParser {
 public:
  LineParser(const std::string& path, int line, const char* const* column_names)
      : path_(path), line_(line), names_(column_names) {}

  std::string Where() const { return path_ + ":" + std::to_string(line_) + ": "; }

  std::string Column(int index) const {
    return "column " + std::to_string(index + 1) + " (" + names_[index] + ")";
  }

  Expected<double> Number(std::string_view field, int index) const {
    const auto value = ParseDouble(field);
    if (!value) {
      return Error{Where() + Column(index) + ": '" + std::string(field) + "' is not a number"};
    }
    if (!std::isfinite(*value)) {
      return Error{Where() + Column(index) + " is not finite ('" + std::string(field) + "')"};
    }
    return *value;
  }

  Expected<int64_t> NanosecondStamp(std::string_view field, int index) const {
    const auto value = ParseInteger<int64_t>(field);
    if (!value) {
      return Error{Where() + Column(index) + ": '" + std::string(field) +
                   "' is not an integer nanosecond stamp"};
    }
    return *value;
  }

  Expected<int64_t> SecondsStamp(std::string_view field, int index) const {
    const auto value = ParseSecondsToNs(field);
    if (!value) {
      return Error{Where() + Column(index) + ": '" + std::string(field) +
                   "' is not a time in seconds"};
    }
    return *value;
  }

  Expected<int> Segment(std::string_view field, int index) const {
    const auto value = ParseInteger<int>(field);
    if (!value) {
      return Error{Where() + Column(index) + ": '" + std::string(field) +
                   "' is not an integer segment id"};
    }
    return *value;
  }

 private:
  const std::string& path_;
  int line_;
  const char* const* names_;
};

struct ParsedLine {
  int64_t t_ns = 0;
  double q_wxyz[4] = {1, 0, 0, 0};
  double c[3] = {0, 0, 0};
  int segment = 0;
};

// Parses the fields of one data line of `format`. `fields` has a valid column count.
Expected<ParsedLine> ParseFields(const std::vector<std::string_view>& fields,
                                 TrajectoryFormat format, const LineParser& p) {
  ParsedLine out;
  // Column index of C (x, y, z) and q (w, x, y, z) per format; t is column 0 in all.
  constexpr int t_col = 0;
  std::array<int, 3> c_cols{};
  std::array<int, 4> q_cols{};
  switch (format) {
    case TrajectoryFormat::kTum:
      c_cols = {1, 2, 3};
      q_cols = {7, 4, 5, 6};
      break;
    case TrajectoryFormat::kEurocCsv:
      c_cols = {1, 2, 3};
      q_cols = {4, 5, 6, 7};
      break;
    case TrajectoryFormat::kNative:
      c_cols = {5, 6, 7};
      q_cols = {1, 2, 3, 4};
      break;
  }
  auto t = format == TrajectoryFormat::kTum ? p.SecondsStamp(fields[t_col], t_col)
                                            : p.NanosecondStamp(fields[t_col], t_col);
  if (!t) return Error{t.error()};
  out.t_ns = *t;
  for (int i = 0; i < 3; ++i) {
    auto v = p.Number(fields[c_cols[i]], c_cols[i]);
    if (!v) return Error{v.error()};
    out.c[i] = *v;
  }
  for (int i = 0; i < 4; ++i) {
    auto v = p.Number(fields[q_cols[i]], q_cols[i]);
    if (!v) return Error{v.error()};
    out.q_wxyz[i] = *v;
  }
  if (format != TrajectoryFormat::kEurocCsv && fields.size() > kPoseColumns) {
    auto s = p.Segment(fields[kPoseColumns], kPoseColumns);
    if (!s) return Error{s.error()};
    out.segment = *s;
  }
  return out;
}

const char* const* ColumnNames(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return kTumColumns.data();
    case TrajectoryFormat::kEurocCsv:
      return kEurocColumns.data();
    case TrajectoryFormat::kNative:
      return kNativeColumns.data();
  }
  return kTumColumns.data();
}

TrajectoryFormat DetectFormat(std::string_view first_data_line, bool native_header) {
  if (first_data_line.find(',') != std::string_view::npos) return TrajectoryFormat::kEurocCsv;
  if (native_header) return TrajectoryFormat::kNative;
  const auto fields = SplitWhitespace(first_data_line);
  if (!fields.empty() && IsPlainInteger(fields[0])) {
    const auto t = ParseInteger<int64_t>(fields[0]);
    if (t && (*t >= 1'000'000'000'000LL || *t <= -1'000'000'000'000LL)) {
      return TrajectoryFormat::kNative;
    }
  }
  return TrajectoryFormat::kTum;
}

std::string FormatRange(const TimedTrajectory& t) {
  std::array<char, 96> buf{};
  std::snprintf(buf.data(), buf.size(), "%.3f..%.3f s", static_cast<double>(t.t_ns.front()) * 1e-9,
                static_cast<double>(t.t_ns.back()) * 1e-9);
  return t.name + " " + buf.data();
}

// Index of the stamp in sorted `stamps` nearest to `t` (the earlier one on a tie).
size_t Nearest(const std::vector<int64_t>& stamps, int64_t t) {
  const auto it = std::lower_bound(stamps.begin(), stamps.end(), t);
  if (it == stamps.begin()) return 0;
  if (it == stamps.end()) return stamps.size() - 1;
  const size_t hi = static_cast<size_t>(it - stamps.begin());
  // Compare distances without overflow: both differences are non-negative.
  const uint64_t d_hi = static_cast<uint64_t>(*it) - static_cast<uint64_t>(t);
  const uint64_t d_lo = static_cast<uint64_t>(t) - static_cast<uint64_t>(*(it - 1));
  return d_lo <= d_hi ? hi - 1 : hi;
}

uint64_t AbsDiff(int64_t a, int64_t b) {
  return a >= b ? static_cast<uint64_t>(a) - static_cast<uint64_t>(b)
                : static_cast<uint64_t>(b) - static_cast<uint64_t>(a);
}

std::string CheckTrajectory(const TimedTrajectory& t) {
  if (t.t_ns.empty()) return "camera '" + t.name + "' has no poses";
  if (t.poses.size() != t.t_ns.size() ||
      (!t.segment.empty() && t.segment.size() != t.t_ns.size())) {
    return "camera '" + t.name + "': t_ns, poses and segment differ in size";
  }
  if (!std::is_sorted(t.t_ns.begin(), t.t_ns.end())) {
    return "camera '" + t.name + "': stamps are not sorted";
  }
  return "";
}

CameraTrack TrackOf(const TimedTrajectory& t, const std::vector<size_t>& indices) {
  CameraTrack track;
  track.name = t.name;
  track.poses.reserve(indices.size());
  track.segment.reserve(indices.size());
  for (const size_t i : indices) {
    track.poses.push_back(t.poses[i]);
    track.segment.push_back(t.segment.empty() ? 0 : t.segment[i]);
  }
  return track;
}

Status WriteTrajectory(const std::string& path, const TimedTrajectory& trajectory,
                       TrajectoryFormat format) {
  if (trajectory.poses.size() != trajectory.t_ns.size() ||
      (!trajectory.segment.empty() && trajectory.segment.size() != trajectory.t_ns.size())) {
    return Error{"cannot write '" + path + "': t_ns, poses and segment differ in size"};
  }
  const bool with_segment =
      format == TrajectoryFormat::kNative ||
      std::any_of(trajectory.segment.begin(), trajectory.segment.end(), [](int s) { return s; });
  std::string out;
  if (format == TrajectoryFormat::kNative) {
    out += "# rigcal poses\n# t_ns qw qx qy qz Cx Cy Cz segment\n";
  } else {
    out += with_segment ? "# t tx ty tz qx qy qz qw segment\n" : "# t tx ty tz qx qy qz qw\n";
  }
  for (size_t k = 0; k < trajectory.size(); ++k) {
    const Pose& pose = trajectory.poses[k];
    const auto& q = pose.q;
    const auto& c = pose.C;
    if (format == TrajectoryFormat::kNative) {
      out += std::to_string(trajectory.t_ns[k]);
      for (const double v : {q.w(), q.x(), q.y(), q.z(), c.x(), c.y(), c.z()}) {
        out += ' ' + ShortestText(v);
      }
    } else {
      out += FormatNsAsSeconds(trajectory.t_ns[k]);
      for (const double v : {c.x(), c.y(), c.z(), q.x(), q.y(), q.z(), q.w()}) {
        out += ' ' + ShortestText(v);
      }
    }
    if (with_segment) {
      out += ' ' + std::to_string(trajectory.segment.empty() ? 0 : trajectory.segment[k]);
    }
    out += '\n';
  }
  return WriteFileAtomically(path, out);
}

}  // namespace

std::string ToString(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "TUM";
    case TrajectoryFormat::kEurocCsv:
      return "EuRoC CSV";
    case TrajectoryFormat::kNative:
      return "rigcal native";
  }
  return "unknown";
}

std::optional<int64_t> ParseSecondsToNs(std::string_view text) {
  size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '+' || text[i] == '-')) negative = text[i++] == '-';
  std::string digits;
  int64_t frac_len = 0;
  bool seen_point = false;
  bool any_digit = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c >= '0' && c <= '9') {
      any_digit = true;
      if (!digits.empty() || c != '0') digits += c;  // leading zeros carry no value
      if (seen_point) ++frac_len;
    } else if (c == '.' && !seen_point) {
      seen_point = true;
    } else {
      break;
    }
  }
  if (!any_digit) return std::nullopt;
  int64_t exponent = 0;
  if (i < text.size() && (text[i] == 'e' || text[i] == 'E')) {
    ++i;
    bool exp_negative = false;
    if (i < text.size() && (text[i] == '+' || text[i] == '-')) exp_negative = text[i++] == '-';
    if (i == text.size()) return std::nullopt;
    for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i) {
      exponent = std::min<int64_t>(exponent * 10 + (text[i] - '0'), 100000);
    }
    if (exp_negative) exponent = -exponent;
  }
  if (i != text.size()) return std::nullopt;

  // Value in ns = digits * 10^shift. Trailing zeros of a fraction were kept in `digits` and
  // counted in frac_len, so they cancel here.
  const int64_t shift = exponent - frac_len + 9;
  bool round_up = false;
  if (shift < 0) {
    const auto drop = static_cast<size_t>(-shift);
    if (drop > digits.size()) {
      digits.clear();
    } else {
      round_up = digits[digits.size() - drop] >= '5';
      digits.resize(digits.size() - drop);
    }
  } else if (!digits.empty()) {
    if (shift > 19) return std::nullopt;
    digits.append(static_cast<size_t>(shift), '0');
  }
  if (digits.size() > 19) return std::nullopt;
  uint64_t magnitude = 0;
  for (const char c : digits) magnitude = magnitude * 10 + static_cast<uint64_t>(c - '0');
  if (digits.size() == 19 && digits > "9223372036854775807") return std::nullopt;
  if (round_up) ++magnitude;
  constexpr auto kMax = static_cast<uint64_t>(std::numeric_limits<int64_t>::max());
  if (magnitude > kMax) return std::nullopt;
  const auto value = static_cast<int64_t>(magnitude);
  return negative ? -value : value;
}

Expected<TimedTrajectory> ReadKittiTrajectory(const std::string& poses_path,
                                              const std::string& times_path) {
  constexpr double kOrthonormalTolerance = 1e-4;
  static constexpr std::array<const char*, 12> kKittiColumns = {
      "r11", "r12", "r13", "tx", "r21", "r22", "r23", "ty", "r31", "r32", "r33", "tz"};
  static constexpr std::array<const char*, 1> kTimeColumns = {"t [s]"};
  std::error_code ec;
  for (const std::string* path : {&poses_path, &times_path}) {
    if (std::filesystem::is_directory(*path, ec)) return Error{*path + ": is a directory"};
  }
  std::ifstream poses_in(poses_path);
  if (!poses_in) return Error{poses_path + ": cannot open: " + std::strerror(errno)};
  std::ifstream times_in(times_path);
  if (!times_in) return Error{times_path + ": cannot open: " + std::strerror(errno)};

  TimedTrajectory trajectory;
  trajectory.name = std::filesystem::path(poses_path).stem().string();
  std::string text;
  int line = 0;
  while (std::getline(poses_in, text)) {
    ++line;
    const std::string_view trimmed = Trim(text);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const auto fields = SplitWhitespace(trimmed);
    const LineParser p(poses_path, line, kKittiColumns.data());
    if (fields.size() != kKittiColumns.size()) {
      return Error{p.Where() + "expected 12 numbers (a row-major 3x4 matrix [R | t]), got " +
                   std::to_string(fields.size())};
    }
    Eigen::Matrix<double, 3, 4> m;
    for (int i = 0; i < 12; ++i) {
      auto v = p.Number(fields[i], i);
      if (!v) return Error{v.error()};
      m(i / 4, i % 4) = *v;
    }
    const Eigen::Matrix3d r = m.leftCols<3>();
    const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(error <= kOrthonormalTolerance) || !(r.determinant() > 0.0)) {
      return Error{p.Where() + "the rotation block is not a rotation (|R^T R - I| = " +
                   SignificantText(error, 9) + ", det " + SignificantText(r.determinant(), 9) +
                   ")"};
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Pose pose;
    pose.q = Eigen::Quaterniond(svd.matrixU() * svd.matrixV().transpose()).normalized();
    pose.C = m.col(3);
    trajectory.poses.push_back(pose);
  }
  line = 0;
  std::vector<int> line_of_time;
  while (std::getline(times_in, text)) {
    ++line;
    const std::string_view trimmed = Trim(text);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const auto fields = SplitWhitespace(trimmed);
    const LineParser p(times_path, line, kTimeColumns.data());
    if (fields.size() != 1) {
      return Error{p.Where() + "expected one time in seconds, got " +
                   std::to_string(fields.size()) + " columns"};
    }
    auto t = p.SecondsStamp(fields[0], 0);
    if (!t) return Error{t.error()};
    if (!trajectory.t_ns.empty() && *t <= trajectory.t_ns.back()) {
      return Error{p.Where() + "time does not increase (line " +
                   std::to_string(line_of_time.back()) + " has " +
                   FormatNsAsSeconds(trajectory.t_ns.back()) + " s)"};
    }
    trajectory.t_ns.push_back(*t);
    line_of_time.push_back(line);
  }
  if (trajectory.poses.empty()) return Error{poses_path + ": no poses"};
  if (trajectory.t_ns.size() != trajectory.poses.size()) {
    return Error{times_path + ": " + std::to_string(trajectory.t_ns.size()) + " times for " +
                 std::to_string(trajectory.poses.size()) + " poses in " + poses_path};
  }
  trajectory.segment.assign(trajectory.size(), 0);
  return trajectory;
}

Expected<TimedTrajectory> ReadTrajectory(const std::string& path,
                                         const TrajectoryReadOptions& options,
                                         TrajectoryFormat* format_out) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return Error{path + ": is a directory"};
  std::ifstream in(path);
  if (!in) return Error{path + ": cannot open: " + std::strerror(errno)};

  TimedTrajectory trajectory;
  trajectory.name = std::filesystem::path(path).stem().string();
  std::optional<TrajectoryFormat> format;
  bool native_header = false;
  size_t expected_columns = 0;
  int first_data_line = 0;
  std::vector<int> line_of_pose;
  int normalised = 0;
  double max_norm_error = 0.0;

  std::string raw;
  int line = 0;
  while (std::getline(in, raw)) {
    ++line;
    const std::string_view text = Trim(raw);
    if (text.empty()) continue;
    if (text[0] == '#') {
      if (!format && Trim(text.substr(1)).starts_with("rigcal poses")) {
        native_header = true;
      }
      continue;
    }
    if (!format) {
      format = DetectFormat(text, native_header);
      first_data_line = line;
    }
    const LineParser parser(path, line, ColumnNames(*format));
    const auto fields =
        *format == TrajectoryFormat::kEurocCsv ? SplitComma(text) : SplitWhitespace(text);
    if (*format == TrajectoryFormat::kEurocCsv) {
      if (fields.size() < kPoseColumns) {
        return Error{parser.Where() + "expected at least 8 comma-separated columns " +
                     "(timestamp [ns], p_x, p_y, p_z, q_w, q_x, q_y, q_z), got " +
                     std::to_string(fields.size())};
      }
    } else if (expected_columns == 0) {
      if (fields.size() != kPoseColumns && fields.size() != kPoseColumns + 1) {
        return Error{parser.Where() + "expected 8 or 9 columns (" + ToString(*format) +
                     " format), got " + std::to_string(fields.size())};
      }
      expected_columns = fields.size();
    } else if (fields.size() != expected_columns) {
      return Error{parser.Where() + "expected " + std::to_string(expected_columns) +
                   " columns like line " + std::to_string(first_data_line) + ", got " +
                   std::to_string(fields.size())};
    }

    auto parsed = ParseFields(fields, *format, parser);
    if (!parsed) return Error{parsed.error()};
    const ParsedLine& p = *parsed;

    if (!trajectory.t_ns.empty() && p.t_ns <= trajectory.t_ns.back()) {
      const std::string previous = std::to_string(line_of_pose.back());
      if (p.t_ns == trajectory.t_ns.back()) {
        return Error{parser.Where() + "duplicate time stamp " + FormatNsAsSeconds(p.t_ns) +
                     " s (same as line " + previous + ")"};
      }
      return Error{parser.Where() + "time goes backwards: " + FormatNsAsSeconds(p.t_ns) +
                   " s after " + FormatNsAsSeconds(trajectory.t_ns.back()) + " s on line " +
                   previous};
    }

    const Eigen::Vector4d q(p.q_wxyz[0], p.q_wxyz[1], p.q_wxyz[2], p.q_wxyz[3]);
    const double norm = q.norm();
    const double norm_error = std::abs(norm - 1.0);
    if (!(norm_error <= options.max_quaternion_norm_error)) {
      return Error{parser.Where() + "quaternion (w, x, y, z) = (" + SignificantText(q[0], 9) +
                   ", " + SignificantText(q[1], 9) + ", " + SignificantText(q[2], 9) + ", " +
                   SignificantText(q[3], 9) + ") has norm " + SignificantText(norm, 9) +
                   ", not 1 within " + SignificantText(options.max_quaternion_norm_error, 9)};
    }
    if (norm_error > kSilentNormError) {
      ++normalised;
      max_norm_error = std::max(max_norm_error, norm_error);
    }
    Pose pose;
    pose.q = Eigen::Quaterniond(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm);
    pose.C = Eigen::Vector3d(p.c[0], p.c[1], p.c[2]);
    trajectory.t_ns.push_back(p.t_ns);
    trajectory.poses.push_back(pose);
    trajectory.segment.push_back(p.segment);
    line_of_pose.push_back(line);
  }
  if (in.bad()) return Error{path + ": read error after line " + std::to_string(line)};
  if (trajectory.t_ns.empty()) {
    return Error{path + ": no poses (the file is empty or has only comments)"};
  }
  if (normalised > 0) {
    ModuleLogger("tools")->warn("{}: normalised {} of {} quaternions (norms off by up to {:.2g})",
                                path, normalised, trajectory.size(), max_norm_error);
  }
  if (format_out) *format_out = *format;
  return trajectory;
}

Status WriteTrajectoryTum(const std::string& path, const TimedTrajectory& trajectory) {
  return WriteTrajectory(path, trajectory, TrajectoryFormat::kTum);
}

Status WriteTrajectoryNative(const std::string& path, const TimedTrajectory& trajectory) {
  return WriteTrajectory(path, trajectory, TrajectoryFormat::kNative);
}

Expected<RigRecording> MatchTrajectories(const TimedTrajectory& master,
                                         const std::vector<TimedTrajectory>& slaves,
                                         int64_t tolerance_ns) {
  if (tolerance_ns < 0) return Error{"the matching tolerance must not be negative"};
  if (slaves.empty()) return Error{"no slave trajectories to match"};
  std::vector<const TimedTrajectory*> all = {&master};
  for (const auto& s : slaves) all.push_back(&s);
  for (size_t i = 0; i < all.size(); ++i) {
    if (const std::string problem = CheckTrajectory(*all[i]); !problem.empty()) {
      return Error{problem};
    }
    for (size_t j = 0; j < i; ++j) {
      if (all[i]->name == all[j]->name) {
        return Error{"two cameras are named '" + all[i]->name +
                     "' (camera names are file stems and must differ)"};
      }
    }
  }

  // Common time range, widened by the tolerance.
  int64_t lo = master.t_ns.front();
  int64_t hi = master.t_ns.back();
  for (const auto& s : slaves) {
    lo = std::max(lo, s.t_ns.front());
    hi = std::min(hi, s.t_ns.back());
  }
  if (lo > hi && AbsDiff(lo, hi) > static_cast<uint64_t>(tolerance_ns)) {
    std::string message = "no overlapping time range: master " + FormatRange(master);
    for (const auto& s : slaves) message += ", " + FormatRange(s);
    return Error{message};
  }

  // matched[s][k]: index into slave s matched to master stamp k, or npos.
  constexpr size_t kNone = std::numeric_limits<size_t>::max();
  std::vector<std::vector<size_t>> matched(slaves.size(),
                                           std::vector<size_t>(master.size(), kNone));
  std::vector<int> count(slaves.size(), 0);
  for (size_t s = 0; s < slaves.size(); ++s) {
    const auto& slave_t = slaves[s].t_ns;
    for (size_t k = 0; k < master.size(); ++k) {
      const size_t j = Nearest(slave_t, master.t_ns[k]);
      if (AbsDiff(slave_t[j], master.t_ns[k]) > static_cast<uint64_t>(tolerance_ns)) continue;
      if (Nearest(master.t_ns, slave_t[j]) != k) continue;
      matched[s][k] = j;
      ++count[s];
    }
  }

  std::vector<size_t> master_indices;
  std::vector<std::vector<size_t>> slave_indices(slaves.size());
  for (size_t k = 0; k < master.size(); ++k) {
    const bool in_all = std::all_of(matched.begin(), matched.end(),
                                    [k](const std::vector<size_t>& m) { return m[k] != kNone; });
    if (!in_all) continue;
    master_indices.push_back(k);
    for (size_t s = 0; s < slaves.size(); ++s) slave_indices[s].push_back(matched[s][k]);
  }
  if (master_indices.size() < 2) {
    std::string message = "only " + std::to_string(master_indices.size()) +
                          " master stamps have a pose in every slave within " +
                          SignificantText(static_cast<double>(tolerance_ns) * 1e-6, 9) +
                          " ms (need at least 2); per slave:";
    for (size_t s = 0; s < slaves.size(); ++s) {
      message += (s ? ", " : " ") + slaves[s].name + " matched " + std::to_string(count[s]) +
                 " of " + std::to_string(master.size());
    }
    return Error{message};
  }

  RigRecording recording;
  recording.t_ns.reserve(master_indices.size());
  for (const size_t k : master_indices) recording.t_ns.push_back(master.t_ns[k]);
  recording.master = TrackOf(master, master_indices);
  for (size_t s = 0; s < slaves.size(); ++s) {
    recording.slaves.push_back(TrackOf(slaves[s], slave_indices[s]));
  }
  return recording;
}

}  // namespace rigcal::tools
