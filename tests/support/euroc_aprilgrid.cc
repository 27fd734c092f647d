// SPDX-License-Identifier: Apache-2.0
#include "support/euroc_aprilgrid.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

// OpenCV 4.6 headers do enum arithmetic that C++20 deprecates; keep the build log clean.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-enum-enum-conversion"
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#pragma GCC diagnostic pop

#include "rigcal/base/robust_statistics.h"

namespace rigcal::support {
namespace {

namespace fs = std::filesystem;

// The numbers of the flow sequence `key: [a, b, ...]` (may span lines) inside the top-level
// section `section:` of a small YAML file. Enough for config.yaml; not a YAML parser.
Expected<std::vector<double>> NumberList(const std::string& text, const std::string& section,
                                         const std::string& key) {
  size_t pos = 0;
  size_t section_begin = std::string::npos;
  while (pos < text.size()) {
    size_t eol = text.find('\n', pos);
    if (eol == std::string::npos) eol = text.size();
    if (text.compare(pos, section.size() + 1, section + ":") == 0) {
      section_begin = eol;
      break;
    }
    pos = eol + 1;
  }
  if (section_begin == std::string::npos) return Error{"no section '" + section + "'"};
  // The section ends at the next line that starts in column 0 with a non-space, non-comment.
  size_t section_end = text.size();
  for (size_t p = section_begin; p + 1 < text.size(); ++p) {
    if (text[p] == '\n' && !std::isspace(static_cast<unsigned char>(text[p + 1])) &&
        text[p + 1] != '#') {
      section_end = p;
      break;
    }
  }
  const std::string body = text.substr(section_begin, section_end - section_begin);
  const size_t key_pos = body.find(key + ":");
  if (key_pos == std::string::npos) return Error{"no '" + key + "' in '" + section + "'"};
  const size_t open = body.find('[', key_pos);
  const size_t close = body.find(']', key_pos);
  if (open == std::string::npos || close == std::string::npos || close < open) {
    return Error{"'" + section + "." + key + "' is not a [..] list"};
  }
  std::string list = body.substr(open + 1, close - open - 1);
  std::replace(list.begin(), list.end(), ',', ' ');
  std::istringstream in(list);
  std::vector<double> values;
  double v = 0.0;
  while (in >> v) values.push_back(v);
  if (!in.eof()) return Error{"'" + section + "." + key + "' holds a non-number"};
  return values;
}

Expected<PinholeRadtan> CameraFromConfig(const std::string& text, const std::string& cam) {
  auto proj = NumberList(text, cam, "proj_params");
  if (!proj) return Error{proj.error()};
  auto dist = NumberList(text, cam, "dist_params");
  if (!dist) return Error{dist.error()};
  if (proj->size() != 4 || dist->size() != 4) {
    return Error{cam + ": expected 4 proj_params and 4 dist_params (pinhole radtan4)"};
  }
  PinholeRadtan c;
  c.fx = (*proj)[0];
  c.fy = (*proj)[1];
  c.cx = (*proj)[2];
  c.cy = (*proj)[3];
  for (int i = 0; i < 4; ++i) c.dist[i] = (*dist)[i];
  return c;
}

cv::Matx33d CameraMatrix(const PinholeRadtan& c) {
  return cv::Matx33d(c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0);
}

cv::Mat DistCoeffs(const PinholeRadtan& c) {
  return (cv::Mat_<double>(4, 1) << c.dist[0], c.dist[1], c.dist[2], c.dist[3]);
}

// Mean reprojection error [px] of the pose (rvec, tvec) = cam_from_target.
double MeanReprojection(const std::vector<cv::Point3d>& object,
                        const std::vector<cv::Point2d>& image, const cv::Matx33d& K,
                        const cv::Mat& dist, const cv::Mat& rvec, const cv::Mat& tvec) {
  std::vector<cv::Point2d> projected;
  cv::projectPoints(object, rvec, tvec, K, dist, projected);
  double sum = 0.0;
  for (size_t i = 0; i < image.size(); ++i) sum += cv::norm(projected[i] - image[i]);
  return sum / static_cast<double>(image.size());
}

std::string FormatSeconds(int64_t t_ns) {
  // Exact decimal seconds from integer nanoseconds (no double rounding).
  const bool negative = t_ns < 0;
  const uint64_t abs_ns = negative ? static_cast<uint64_t>(-(t_ns + 1)) + 1 : t_ns;
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(abs_ns / 1000000000ULL),
                static_cast<unsigned long long>(abs_ns % 1000000000ULL));
  return buf;
}

}  // namespace

std::string EurocAprilGridDir() {
  return std::string(RIGCAL_SHARED_DATA_DIR) + "/euroc_calib_aprilgrid/imu_april";
}

bool EurocAprilGridAvailable(std::string* reason) {
  const fs::path dir = EurocAprilGridDir();
  for (const char* entry : {"config.yaml", "cam0", "cam1"}) {
    std::error_code ec;
    if (!fs::exists(dir / entry, ec)) {
      if (reason != nullptr) {
        *reason = "EuRoC AprilGrid data not found: " + (dir / entry).string() +
                  " is missing (set RIGCAL_SHARED_DATA_DIR at configure time)";
      }
      return false;
    }
  }
  return true;
}

Expected<EurocAprilGridConfig> LoadEurocAprilGridConfig(const std::string& dir) {
  const std::string path = dir + "/config.yaml";
  std::ifstream in(path);
  if (!in) return Error{"cannot open " + path};
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();

  EurocAprilGridConfig config;
  auto cam0 = CameraFromConfig(text, "cam0");
  if (!cam0) return Error{path + ": " + cam0.error()};
  auto cam1 = CameraFromConfig(text, "cam1");
  if (!cam1) return Error{path + ": " + cam1.error()};
  config.cam0 = *cam0;
  config.cam1 = *cam1;

  auto data = NumberList(text, "T_cam0_cam1", "data");
  if (!data) return Error{path + ": " + data.error()};
  if (data->size() != 16) return Error{path + ": T_cam0_cam1.data must hold 16 numbers"};
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) T(r, c) = (*data)[4 * r + c];
  }
  // The stored rotation is orthonormal to ~1e-9; re-orthonormalise through the quaternion.
  config.cam0_from_cam1.q =
      Eigen::Quaterniond(Eigen::Matrix3d(T.topLeftCorner<3, 3>())).normalized();
  config.cam0_from_cam1.C = T.topRightCorner<3, 1>();
  config.cam0_from_cam1.scale = 1.0;
  return config;
}

Expected<std::vector<AprilGridFrame>> LoadAprilGridFrames(const std::string& camera_dir) {
  std::error_code ec;
  std::vector<std::pair<int64_t, fs::path>> files;
  for (const auto& entry : fs::directory_iterator(camera_dir, ec)) {
    if (entry.path().extension() != ".csv") continue;
    const std::string stem = entry.path().stem().string();
    char* end = nullptr;
    const long long t = std::strtoll(stem.c_str(), &end, 10);
    if (end == stem.c_str() || *end != '\0') {
      return Error{entry.path().string() + ": file name is not <t_ns>.csv"};
    }
    files.emplace_back(static_cast<int64_t>(t), entry.path());
  }
  if (ec) return Error{"cannot list " + camera_dir + ": " + ec.message()};
  if (files.empty()) return Error{"no <t_ns>.csv files in " + camera_dir};
  std::sort(files.begin(), files.end());

  std::vector<AprilGridFrame> frames;
  frames.reserve(files.size());
  for (const auto& [t_ns, path] : files) {
    std::ifstream in(path);
    if (!in) return Error{"cannot open " + path.string()};
    AprilGridFrame frame;
    frame.t_ns = t_ns;
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      if (line.empty() || line[0] == '#') continue;
      std::replace(line.begin(), line.end(), ',', ' ');
      std::istringstream fields(line);
      double v[12];
      for (double& x : v) fields >> x;
      if (!fields) {
        return Error{path.string() + ":" + std::to_string(line_no) + ": expected 12 numbers"};
      }
      // ts, tag_rows, tag_cols, tag_size, tag_spacing, kp_x, kp_y, p_x, p_y, p_z, ...
      frame.pixels.emplace_back(v[5], v[6]);
      frame.target_points.emplace_back(v[7], v[8], v[9]);
    }
    frames.push_back(std::move(frame));
  }
  return frames;
}

std::vector<TargetPose> EstimateTargetPoses(const std::vector<AprilGridFrame>& frames,
                                            const PinholeRadtan& camera, const PnpOptions& options,
                                            PnpStats* stats) {
  PnpStats local;
  const cv::Matx33d K = CameraMatrix(camera);
  const cv::Mat dist = DistCoeffs(camera);
  std::vector<TargetPose> poses;
  std::vector<double> errors;
  for (const AprilGridFrame& frame : frames) {
    ++local.frames;
    const int n = static_cast<int>(frame.pixels.size());
    if (n < std::max(options.min_corners, 4)) {
      ++local.too_few_corners;
      continue;
    }
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    object.reserve(n);
    image.reserve(n);
    for (int i = 0; i < n; ++i) {
      object.emplace_back(frame.target_points[i].x(), frame.target_points[i].y(),
                          frame.target_points[i].z());
      image.emplace_back(frame.pixels[i].x(), frame.pixels[i].y());
    }
    cv::Mat rvec, tvec;
    bool ok = false;
    try {
      // IPPE: closed form for planar targets (the AprilGrid has z = 0), then LM refinement of
      // the reprojection error through the distortion model.
      ok = cv::solvePnP(object, image, K, dist, rvec, tvec, false, cv::SOLVEPNP_IPPE);
      if (ok) cv::solvePnPRefineLM(object, image, K, dist, rvec, tvec);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || !cv::checkRange(rvec) || !cv::checkRange(tvec)) {
      ++local.pnp_failed;
      continue;
    }
    const double err = MeanReprojection(object, image, K, dist, rvec, tvec);
    if (!(err <= options.max_mean_reproj_px)) {
      ++local.high_reprojection;
      continue;
    }
    cv::Matx33d R_cam_from_target;
    cv::Rodrigues(rvec, R_cam_from_target);
    Eigen::Matrix3d R;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R(r, c) = R_cam_from_target(r, c);
    }
    const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
    TargetPose pose;
    pose.t_ns = frame.t_ns;
    // p_cam = R p_target + t  =>  target_from_cam = [R^T | -R^T t].
    pose.target_from_cam.q = Eigen::Quaterniond(R.transpose()).normalized();
    pose.target_from_cam.C = -R.transpose() * t;
    pose.mean_reproj_px = err;
    pose.corners = n;
    poses.push_back(pose);
    errors.push_back(err);
    ++local.accepted;
  }
  if (!errors.empty()) local.median_reproj_px = UpperMedian(std::move(errors));
  if (stats != nullptr) *stats = local;
  return poses;
}

Expected<EurocRig> LoadEurocAprilGridRig(const PnpOptions& options) {
  const std::string dir = EurocAprilGridDir();
  auto config = LoadEurocAprilGridConfig(dir);
  if (!config) return Error{config.error()};
  auto frames0 = LoadAprilGridFrames(dir + "/cam0");
  if (!frames0) return Error{frames0.error()};
  auto frames1 = LoadAprilGridFrames(dir + "/cam1");
  if (!frames1) return Error{frames1.error()};

  EurocRig rig;
  const auto poses0 = EstimateTargetPoses(*frames0, config->cam0, options, &rig.cam0_stats);
  const auto poses1 = EstimateTargetPoses(*frames1, config->cam1, options, &rig.cam1_stats);
  std::map<int64_t, const TargetPose*> by_time1;
  for (const TargetPose& p : poses1) by_time1[p.t_ns] = &p;

  rig.recording.master.name = "cam0";
  CameraTrack slave;
  slave.name = "cam1";
  for (const TargetPose& p0 : poses0) {
    auto it = by_time1.find(p0.t_ns);
    if (it == by_time1.end()) continue;
    rig.recording.t_ns.push_back(p0.t_ns);
    rig.recording.master.poses.push_back(p0.target_from_cam);
    rig.recording.master.segment.push_back(0);
    slave.poses.push_back(it->second->target_from_cam);
    slave.segment.push_back(0);
  }
  rig.recording.slaves.push_back(std::move(slave));
  rig.truth = config->cam0_from_cam1;
  if (rig.recording.size() < 3) return Error{"fewer than 3 frames with a pose in both cameras"};
  return rig;
}

void ScalePositions(CameraTrack* track, double factor) {
  for (Pose& p : track->poses) p.C *= factor;
}

bool WriteTumTrajectory(const std::string& path, const std::vector<int64_t>& t_ns,
                        const CameraTrack& track, std::string* error) {
  if (t_ns.size() != track.poses.size()) {
    if (error != nullptr) *error = "track '" + track.name + "' size differs from the stamps";
    return false;
  }
  std::ofstream out(path);
  if (!out) {
    if (error != nullptr) *error = "cannot write " + path;
    return false;
  }
  out << "# " << track.name
      << ": timestamp[s] tx ty tz qx qy qz qw (camera centre, world_from_cam)\n";
  out << std::setprecision(17);
  for (size_t k = 0; k < t_ns.size(); ++k) {
    const Pose& p = track.poses[k];
    const Eigen::Quaterniond q = p.q.normalized();
    out << FormatSeconds(t_ns[k]) << ' ' << p.C.x() << ' ' << p.C.y() << ' ' << p.C.z() << ' '
        << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  out.flush();
  if (!out) {
    if (error != nullptr) *error = "error writing " + path;
    return false;
  }
  return true;
}

bool WriteTruthYaml(const std::string& path, const std::string& slave_name,
                    const Similarity& master_from_slave, std::string* error) {
  std::ofstream out(path);
  if (!out) {
    if (error != nullptr) *error = "cannot write " + path;
    return false;
  }
  const Eigen::Quaterniond q = master_from_slave.q.normalized();
  out << std::setprecision(17);
  out << slave_name << ": {q_wxyz: [" << q.w() << ", " << q.x() << ", " << q.y() << ", " << q.z()
      << "], C: [" << master_from_slave.C.x() << ", " << master_from_slave.C.y() << ", "
      << master_from_slave.C.z() << "], scale: " << master_from_slave.scale << "}\n";
  out.flush();
  if (!out) {
    if (error != nullptr) *error = "error writing " + path;
    return false;
  }
  return true;
}

}  // namespace rigcal::support
