// SPDX-License-Identifier: Apache-2.0
#pragma once
// A simulated drive of the 4-camera car rig (config/sim_surround4.yaml) at pose level, through
// the calibration node over memq:// at a multiple of real time, for the load test (2 minutes,
// in make test) and the soak test (1 hour, label soak): poses of a planar (yaw-only) 2-minute
// loop driven again and again, with
// VO noise, every slave's VO re-initialising every 20 s (a new scale), the `left` camera losing
// track for 1 s around each re-initialisation, and the `back` camera dying at 60 % of the drive.
// Pose level, not images: rendering and VO of 4 cameras run at ~1/4 real time on 2 cores; the
// node, sync buffer and estimator are what a long drive can wear out.
//
// Sampled every second of drive time: the heap in use (also at a moment between refinement
// passes) and RSS, the poses published but not yet received by the node (the LCM queue) and the
// sync buffer's fill (RIGCAL_STATUS); at the end the CPU of every named thread.

#include <dirent.h>
#include <gtest/gtest.h>
#include <malloc.h>
#include <pthread.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/calib_node.h"

namespace rigcal::pipeline::surround_drive {

struct Sample {
  double drive_s = 0.0;  // drive time
  double rss_mb = 0.0;
  double heap_mb = 0.0;  // bytes the allocator has handed out and not had back
  // The heap in use at a moment of this second of drive when no refinement pass was in flight
  // (its working copy of the pose history and its solver's memory are transient); NaN when the
  // refinement was in flight at every moment tried.
  double quiet_heap_mb = std::numeric_limits<double>::quiet_NaN();
  int64_t lcm_backlog = 0;  // poses published, not yet received by the node
  int32_t sync_fill = -1;   // from the newest RIGCAL_STATUS (-1: none yet)
};

struct Report {
  std::vector<Sample> samples;
  CalibNodeSummary summary;
  rig_status_t last_status{};   // the newest (written by the node's thread)
  rig_status_t drive_status{};  // the newest at the end of the drive
  bool have_status = false;
  std::vector<Similarity> truth;      // per slave
  std::map<std::string, double> cpu;  // CPU seconds per thread name
  double wall_s = 0.0;
  int64_t published = 0;
  int64_t lost_track = 0;  // poses of `left` withheld (lost track)
  int64_t dead = 0;        // poses of `back` withheld (dead)
};

// Least-squares slope of y over x.
inline double Slope(const std::vector<double>& x, const std::vector<double>& y) {
  const size_t n = x.size();
  if (n < 2) return 0.0;
  double mx = 0, my = 0;
  for (size_t i = 0; i < n; ++i) mx += x[i], my += y[i];
  mx /= n;
  my /= n;
  double sxy = 0, sxx = 0;
  for (size_t i = 0; i < n; ++i) sxy += (x[i] - mx) * (y[i] - my), sxx += (x[i] - mx) * (x[i] - mx);
  return sxx > 0 ? sxy / sxx : 0.0;
}

// Least-squares slope of the lower envelope of y over x: the minimum of every `window` of x. A
// sample taken while the batch refinement holds its work (a transient peak of a megabyte or two)
// drops out; what stays is the floor a leak would raise.
inline double FloorSlope(const std::vector<double>& x, const std::vector<double>& y,
                         double window) {
  std::vector<double> fx, fy;
  for (size_t i = 0; i < x.size();) {
    const double begin = x[i];
    const size_t first = i;
    double lowest = y[i], sum_x = 0.0;
    for (; i < x.size() && x[i] < begin + window; ++i) {
      lowest = std::min(lowest, y[i]);
      sum_x += x[i];
    }
    fx.push_back(sum_x /
                 static_cast<double>(i - first));  // the window's middle, a short last one's too
    fy.push_back(lowest);
  }
  return Slope(fx, fy);
}

// The heap in use (every arena, and the chunks malloc maps on their own): what a leak grows,
// without the pages the allocator keeps or returns, which make RSS move by a megabyte either way.
inline double HeapInUseMb() {
  const struct mallinfo2 m = ::mallinfo2();
  return static_cast<double>(m.uordblks + m.hblkhd) / 1048576.0;
}

// The heap in use when no refinement pass of the node is in flight, read between two reads of
// the passes that show none began or ended; nullopt when one was in flight.
inline std::optional<double> HeapBetweenRefinements(const CalibNode& node) {
  const OnlineCalibrator::RefinementPasses before = node.RefinementPasses();
  if (before.begun != before.ended) return std::nullopt;
  const double heap_mb = HeapInUseMb();
  const OnlineCalibrator::RefinementPasses after = node.RefinementPasses();
  if (after.begun != before.begun || after.ended != before.ended) return std::nullopt;
  return heap_mb;
}

// The memory the process holds: free heap pages go back to the system first (malloc_trim), so a
// transient peak (the batch refinement's work on the pose history) that the allocator keeps for
// reuse is not counted as growth.
inline double RssMb() {
  ::malloc_trim(0);
  std::ifstream statm("/proc/self/statm");
  long size = 0, resident = 0;
  statm >> size >> resident;
  return static_cast<double>(resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) / 1048576.0;
}

// CPU seconds (user + system) per thread name of this process.
inline std::map<std::string, double> ThreadCpu() {
  std::map<std::string, double> cpu;
  DIR* dir = ::opendir("/proc/self/task");
  if (dir == nullptr) return cpu;
  const double tick = static_cast<double>(::sysconf(_SC_CLK_TCK));
  while (const dirent* e = ::readdir(dir)) {
    if (e->d_name[0] == '.') continue;
    const std::string base = std::string("/proc/self/task/") + e->d_name;
    std::string name;
    std::getline(std::ifstream(base + "/comm"), name);
    std::string stat;
    std::getline(std::ifstream(base + "/stat"), stat);
    const size_t close = stat.rfind(')');
    if (close == std::string::npos) continue;
    std::istringstream fields(stat.substr(close + 2));
    std::string skip;
    for (int i = 0; i < 11; ++i) fields >> skip;  // state .. cmajflt (fields 3-13)
    double utime = 0, stime = 0;
    fields >> utime >> stime;
    cpu[name] += (utime + stime) / tick;
  }
  ::closedir(dir);
  return cpu;
}

// RIGCAL_STATUS into the report (the handler runs on the node's LCM thread).
struct StatusSink {
  std::mutex mutex;
  lcm::MessageValidator validator;
  Report* report = nullptr;
};

inline void OnStatus(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel,
                     StatusSink* sink) {
  std::lock_guard<std::mutex> lock(sink->mutex);
  auto msg = sink->validator.Decode<rig_status_t>(channel, rbuf->data, rbuf->data_size);
  if (!msg) return;
  sink->report->last_status = *msg;
  sink->report->have_status = true;
}

// Drives `drive_s` seconds at `speed` times real time (history_sets: the estimator's pose
// history per slave; the default 10000 fills after 500 s of a 20 Hz drive).
inline Report Drive(double drive_s, double speed, int history_sets) {
  Report report;
  const std::string config_path = std::string(RIGCAL_SOURCE_DIR) + "/config/sim_surround4.yaml";
  auto config = io::LoadRigConfig(config_path);
  if (!config) {
    ADD_FAILURE() << config.error();
    return report;
  }
  config->online.estimator.history_sets = history_sets;
  config->publish.status_rate_hz = 5;
  config->publish.extrinsics_rate_hz = 1;
  const std::vector<std::string> names = config->CameraNames();
  std::vector<Similarity> rigs;
  for (size_t i = 1; i < config->cameras.size(); ++i) rigs.push_back(*config->cameras[i].truth);
  report.truth = rigs;

  DriveOptions d;
  d.motion = DriveOptions::Motion::kPlanarYaw;
  d.frame_rate_hz = 20.0;
  d.num_frames = static_cast<int>(drive_s * d.frame_rate_hz);
  d.rotation_noise_deg = 0.05;
  d.position_noise = 0.005;
  d.segment_period_s = 20.0;
  // One loop every 2 minutes, however long the drive: the soak drives the load test's loop 30
  // times (one loop stretched over an hour would turn by a degree per segment, data that do
  // not determine the rig, not wear of the node).
  d.period_s = 120.0;
  const SyntheticDrive drive = GenerateDrive(names, rigs, d);
  const RigRecording& rec = drive.recording;

  ::lcm::LCM bus("memq://");
  StatusSink sink;
  sink.validator = lcm::MessageValidator(lcm::CameraNames(names));
  sink.report = &report;
  bus.subscribeFunction(lcm::kStatusChannel, &OnStatus, &sink);
  CalibNodeOptions options;
  options.camera_timeout_s = std::max(0.5, 5.0 / speed);  // 5 s of drive time
  CalibNode node(*config, options, &bus);
  if (const Status s = node.Open(); !s.ok()) {
    ADD_FAILURE() << s.message();
    return report;
  }
  std::atomic<bool> stop{false};
  std::thread runner([&] {
    pthread_setname_np(pthread_self(), "rigcal-input");
    report.summary = node.Run(stop);
  });
  const lcm::CameraNames camera_names(names);
  pthread_setname_np(pthread_self(), "drive-publish");  // the VO of the four cameras
  const auto start = std::chrono::steady_clock::now();
  const int64_t t0 = rec.t_ns.front();
  double next_sample_s = 0.0;
  for (size_t k = 0; k < rec.size(); ++k) {
    const double t_s = static_cast<double>(rec.t_ns[k] - t0) * 1e-9;
    std::this_thread::sleep_until(start + std::chrono::duration_cast<std::chrono::nanoseconds>(
                                              std::chrono::duration<double>(t_s / speed)));
    for (int cam = 0; cam < static_cast<int>(names.size()); ++cam) {
      if (names[cam] == "back" && t_s > 0.6 * drive_s) {
        ++report.dead;
        continue;
      }
      // `left` loses track for 1 s around every re-initialisation (every 20 s).
      if (names[cam] == "left" && std::fmod(t_s + 0.5, 20.0) < 1.0 && t_s > 1.0) {
        ++report.lost_track;
        continue;
      }
      const CameraPose pose = rec.PoseAt(cam, k);
      auto msg = lcm::CameraPoseToLcm(pose, camera_names, pose.t_ns / 1000);
      if (!msg) continue;
      const std::string channel = lcm::PoseChannel(names[cam]);
      auto bytes = lcm::EncodeMessage(channel, camera_names, *msg);
      if (!bytes) continue;
      bus.publish(channel, bytes->data(), static_cast<unsigned int>(bytes->size()));
      ++report.published;
    }
    // Every publish step (5 ms of wall time at 10x) until the second has a quiet heap sample.
    if (!report.samples.empty() && std::isnan(report.samples.back().quiet_heap_mb)) {
      if (const std::optional<double> heap_mb = HeapBetweenRefinements(node)) {
        report.samples.back().quiet_heap_mb = *heap_mb;
      }
    }
    if (t_s >= next_sample_s) {
      next_sample_s += 1.0;
      Sample s;
      s.drive_s = t_s;
      s.heap_mb = HeapInUseMb();
      if (const std::optional<double> heap_mb = HeapBetweenRefinements(node)) {
        s.quiet_heap_mb = *heap_mb;
      }
      s.rss_mb = RssMb();
      s.lcm_backlog = report.published - node.ReceivedPoses();
      std::lock_guard<std::mutex> lock(sink.mutex);
      s.sync_fill = report.have_status ? report.last_status.sync_fill : -1;
      report.samples.push_back(s);
    }
  }
  // The newest RIGCAL_STATUS of the running node at the end of the drive (the dead camera named).
  std::this_thread::sleep_for(std::chrono::duration<double>(0.3));  // one more status (5 Hz)
  {
    std::lock_guard<std::mutex> lock(sink.mutex);
    report.drive_status = report.last_status;
    report.have_status = report.have_status && report.last_status.utime > 0;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (node.ReceivedPoses() < report.published && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  report.cpu = ThreadCpu();
  stop = true;
  runner.join();
  report.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace rigcal::pipeline::surround_drive
