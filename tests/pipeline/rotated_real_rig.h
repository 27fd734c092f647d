// SPDX-License-Identifier: Apache-2.0
#pragma once
// A two-camera rig made of real frames whose extrinsics are known exactly: the master is a real
// sequence of ../shared/data/real_mono as recorded, the slave a virtual pinhole camera at the
// same centre, rotated by a known master_from_slave, whose every frame is the master's frame
// remapped through the pure-rotation homography
//   u_master ~ K_master * master_from_slave * K_slave^-1 * u_slave
// (bilinear, no pixel outside the master's image: the slave's focal length is the master's
// times `zoom`, the smallest that keeps its whole view inside the master's). Same stamps, so
// master_from_slave is the truth and C = 0 exactly.
//
// What it tests: the whole `rigcal run` chain on real images (capture of two folders, two VOs
// on different (interpolated, zoomed) pixels, matching, the estimator and its σ) against an
// exact truth; with the slave turned by 180° about its optical axis an estimate near the
// identity is off by 180° (but a turn by 180° is nearly its own inverse). What it cannot: a
// baseline (C = 0: the position is tested only for not inventing one), independent scenes (both
// cameras see the same pixels, their VO errors are correlated and the estimate's σ, which treats
// them as independent, is if anything too large), different exposures or rolling shutter. The two
// VOs still initialise and set their scales independently: the slave's odometry scale relative to
// the master's is not known in advance (it is measured against the sequence's metric AprilTag poses
// where they exist).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::pipeline::test {

struct PinholeK {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Eigen::Matrix3d Matrix() const {
    Eigen::Matrix3d k;
    k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
    return k;
  }
};

// slave pixel -> master pixel (homogeneous).
inline Eigen::Matrix3d SlaveToMasterPixels(const PinholeK& master, const PinholeK& slave,
                                           const Eigen::Matrix3d& master_from_slave) {
  return master.Matrix() * master_from_slave * slave.Matrix().inverse();
}

// Whether every border pixel of a width x height slave image maps inside the master's image
// (with `margin_px` to spare for the bilinear interpolation).
inline bool InsideMaster(const Eigen::Matrix3d& slave_to_master, int width, int height,
                         double margin_px) {
  auto inside = [&](double u, double v) {
    const Eigen::Vector3d m = slave_to_master * Eigen::Vector3d(u, v, 1.0);
    if (m.z() <= 0) return false;
    const double x = m.x() / m.z(), y = m.y() / m.z();
    return x >= margin_px && y >= margin_px && x <= width - 1 - margin_px &&
           y <= height - 1 - margin_px;
  };
  for (int u = 0; u < width; ++u) {
    if (!inside(u, 0) || !inside(u, height - 1)) return false;
  }
  for (int v = 0; v < height; ++v) {
    if (!inside(0, v) || !inside(width - 1, v)) return false;
  }
  return true;
}

// The slave's intrinsics: the master's focal lengths times the smallest zoom (in steps of 0.01)
// that keeps the rotated view inside the master's image (1 px to spare), its principal point
// the image centre.
inline PinholeK SlaveIntrinsics(const PinholeK& master, const Eigen::Matrix3d& master_from_slave,
                                int width, int height, double* zoom) {
  for (int step = 100; step <= 300; ++step) {
    *zoom = step / 100.0;
    const PinholeK slave{master.fx * *zoom, master.fy * *zoom, (width - 1) / 2.0,
                         (height - 1) / 2.0};
    if (InsideMaster(SlaveToMasterPixels(master, slave, master_from_slave), width, height, 1.0)) {
      return slave;
    }
  }
  *zoom = 0.0;
  return {};
}

// Writes the slave's frames, frame_0000.png ..., remapped from the master's grey frames.
inline Status WriteSlaveFrames(const std::vector<cv::Mat>& master_grey, const PinholeK& master,
                               const PinholeK& slave, const Eigen::Matrix3d& master_from_slave,
                               const std::filesystem::path& folder) {
  std::filesystem::create_directories(folder);
  const Eigen::Matrix3d h = SlaveToMasterPixels(master, slave, master_from_slave);
  cv::Mat h_cv(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) h_cv.at<double>(r, c) = h(r, c);
  }
  for (size_t k = 0; k < master_grey.size(); ++k) {
    cv::Mat out;
    // dst(u_slave) = src(h * u_slave): the map goes from the destination to the source.
    cv::warpPerspective(master_grey[k], out, h_cv, master_grey[k].size(),
                        cv::INTER_LINEAR | cv::WARP_INVERSE_MAP, cv::BORDER_REPLICATE);
    char name[32];
    std::snprintf(name, sizeof(name), "frame_%04zu.png", k);
    if (!cv::imwrite((folder / name).string(), out)) {
      return Error{"cannot write " + (folder / name).string()};
    }
  }
  return Status::Ok();
}

inline std::string Numbers(const std::vector<double>& values) {
  std::string text = "[";
  char buffer[40];
  for (size_t i = 0; i < values.size(); ++i) {
    std::snprintf(buffer, sizeof(buffer), "%s%.17g", i ? ", " : "", values[i]);
    text += buffer;
  }
  return text + "]";
}

// The rig config: cam0 the master's folder, cam1 the slave's, both at `rate_hz`, cam1's truth
// the construction's mounting.
inline Status WriteRotatedRigConfig(const std::filesystem::path& path, const std::string& name,
                                    const std::string& master_folder, const PinholeK& master,
                                    const std::string& slave_folder, const PinholeK& slave,
                                    const Eigen::Quaterniond& master_from_slave, double rate_hz) {
  std::ofstream out(path);
  out << "# " << name << ": the real frames of " << master_folder
      << " (cam0) and their exact remap\n"
         "# to a virtual camera at the same centre rotated by cam1.truth (cam1).\n"
      << "rig: {name: " << name << ", master: cam0}\n"
      << "cameras:\n"
      << "  - {name: cam0, model: pinhole, resolution: [640, 480], intrinsics: "
      << Numbers({master.fx, master.fy, master.cx, master.cy}) << ",\n"
      << "     device: '" << master_folder << "'}\n"
      << "  - {name: cam1, model: pinhole, resolution: [640, 480], intrinsics: "
      << Numbers({slave.fx, slave.fy, slave.cx, slave.cy}) << ",\n"
      << "     device: '" << slave_folder << "',\n"
      << "     truth: {q_wxyz: "
      << Numbers({master_from_slave.w(), master_from_slave.x(), master_from_slave.y(),
                  master_from_slave.z()})
      << ", C: [0, 0, 0]}}\n"
      << "source: {type: image_folders, rate_hz: " << rate_hz << "}\n";
  out.close();
  if (!out) return Error{"cannot write " + path.string()};
  return Status::Ok();
}

}  // namespace rigcal::pipeline::test
