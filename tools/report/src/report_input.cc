// SPDX-License-Identifier: Apache-2.0
#include "rigcal/report/report_input.h"

#include <algorithm>
#include <cmath>

#include "history_log.h"
#include "motion_analysis.h"
#include "rigcal/io/result_file.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/io/truth_files.h"
#include "rigcal/lcm/slave_view.h"
#include "rigcal/slave_extrinsics_t.hpp"

namespace rigcal::report {
namespace {

using internal::LogContents;

// -1 (unknown on LCM) as NaN.
double Known(double sigma) { return sigma >= 0.0 ? sigma : kUnknown; }

SlaveCalibration FinalSlave(const slave_extrinsics_t& s) {
  SlaveCalibration slave;
  slave.name = s.name;
  slave.estimate.q = lcm::ViewOf(s).q;
  slave.estimate.C = Eigen::Vector3d(s.C[0], s.C[1], s.C[2]);
  slave.estimate.scale = s.scale;
  SegmentScale segment;
  segment.segment = s.segment;
  segment.scale = s.scale;
  segment.std = Known(s.scale_std);
  slave.scales.push_back(segment);
  slave.rot_std_deg = Known(s.rot_std_deg);
  slave.pos_std = Eigen::Vector3d(Known(s.pos_std[0]), Known(s.pos_std[1]), Known(s.pos_std[2]));
  slave.axis_offset_std = Known(s.axis_offset_std);
  slave.motions.used = s.motions_used;
  slave.motions.residual_outlier = s.motions_rejected;
  slave.motions.total = s.motions_used + s.motions_rejected;
  slave.state = lcm::ViewOf(s).state;
  slave.termination =
      IsUsable(slave.state) ? Termination::kSolved : Termination::kInsufficientMotion;
  slave.message = s.message;
  return slave;
}

// The estimate history, the health history and the final table of a log.
Status FillFromLog(const LogContents& log, ReportData* data) {
  if (log.extrinsics.empty()) {
    return Error{data->input + ": no valid RIGCAL_EXTRINSICS message in the log (" +
                 std::to_string(log.events) + " events" +
                 (log.rejected > 0 ? ", " + std::to_string(log.rejected) +
                                         " rejected, first: " + log.first_rejection
                                   : std::string()) +
                 "); record one with `rigcal calib --log in.log --publish-lcm "
                 "file:///tmp/out.log?mode=w`"};
  }
  const rig_extrinsics_t& last = log.extrinsics.back();
  data->master = last.master;
  data->distance_unit = last.distance_unit == rig_extrinsics_t::UNIT_METRE ? "m" : "master units";
  if (last.distance_unit == rig_extrinsics_t::UNIT_METRE) {
    data->metres_per_unit = 1.0;
    data->metres_source = "C in metres (RIGCAL_EXTRINSICS distance_unit)";
  }
  data->extrinsics_messages = static_cast<int64_t>(log.extrinsics.size());
  data->t0_ns = log.extrinsics.front().t_ns;
  for (const rig_extrinsics_t& msg : log.extrinsics) data->t0_ns = std::min(data->t0_ns, msg.t_ns);
  for (const auto& [camera, poses] : log.poses) {
    if (!poses.t_ns.empty()) data->t0_ns = std::min(data->t0_ns, poses.t_ns.front());
  }
  for (const rig_extrinsics_t& msg : log.extrinsics) {
    for (const slave_extrinsics_t& s : msg.slaves) {
      if (std::find(data->slaves.begin(), data->slaves.end(), s.name) == data->slaves.end()) {
        data->slaves.push_back(s.name);
      }
      EstimateSample sample;
      sample.t_s = 1e-9 * static_cast<double>(msg.t_ns - data->t0_ns);
      sample.estimate.q = lcm::ViewOf(s).q;
      sample.estimate.C = Eigen::Vector3d(s.C[0], s.C[1], s.C[2]);
      sample.estimate.scale = s.scale;
      sample.rot_std_deg = Known(s.rot_std_deg);
      sample.pos_std =
          Eigen::Vector3d(Known(s.pos_std[0]), Known(s.pos_std[1]), Known(s.pos_std[2]));
      sample.scale_std = Known(s.scale_std);
      sample.motions_used = s.motions_used;
      sample.state = lcm::ViewOf(s).state;
      data->estimates[s.name].push_back(sample);
    }
  }
  data->final_result.master = last.master;
  for (const slave_extrinsics_t& s : last.slaves)
    data->final_result.slaves.push_back(FinalSlave(s));

  data->status_messages = static_cast<int64_t>(log.status.size());
  if (log.status.empty()) {
    data->notes.push_back("no RIGCAL_STATUS message in the log: no camera health plots");
  } else {
    const int64_t t0_us = log.status.front().utime;
    for (const rig_status_t& msg : log.status) {
      for (const camera_status_t& c : msg.cameras) {
        if (std::find(data->cameras.begin(), data->cameras.end(), c.name) == data->cameras.end()) {
          data->cameras.push_back(c.name);
        }
        CameraHealthSample sample;
        sample.t_s = 1e-6 * static_cast<double>(msg.utime - t0_us);
        sample.fps = c.fps;
        sample.frames_received = c.frames_received;
        sample.dropped = c.dropped_late + c.dropped_duplicate + c.dropped_out_of_order +
                         c.dropped_overflow + c.dropped_never_matched + c.dropped_invalid;
        sample.vo_state = c.vo_state;
        sample.last_pose_age_ms = c.last_pose_age_ms;
        sample.relocalisations = c.relocalisations;
        if (c.time_offset_source == slave_extrinsics_t::TIME_OFFSET_GIVEN ||
            c.time_offset_source == slave_extrinsics_t::TIME_OFFSET_ESTIMATED) {
          sample.time_offset_ms = c.time_offset_s * 1e3;
        }
        sample.clock_jumps = c.clock_jumps;
        data->free_running =
            data->free_running || c.time_offset_source != slave_extrinsics_t::TIME_OFFSET_NONE;
        data->health[c.name].push_back(sample);
      }
    }
  }
  if (log.extrinsics.size() < 3) {
    data->notes.push_back("the log holds only " + std::to_string(log.extrinsics.size()) +
                          " RIGCAL_EXTRINSICS message(s): hardly a history (a replay whose "
                          "timers ran on the wall clock publishes one at its end)");
  }
  return {};
}

void AddLogNotes(const LogContents& log, ReportData* data) {
  if (!log.damage.empty()) data->notes.push_back(log.damage);
  if (log.rejected > 0) {
    data->notes.push_back(
        std::to_string(log.rejected) +
        " message(s) failed validation and were left out; first: " + log.first_rejection);
  }
}

// The poses of the log as odometry trajectories in rig order (master first); empty when the log
// has none of some camera.
std::vector<TimedTrajectory> OdometryOf(const LogContents* log, const ReportData& data) {
  std::vector<TimedTrajectory> odometry;
  if (log == nullptr) return odometry;
  std::vector<std::string> cameras = {data.master};
  cameras.insert(cameras.end(), data.slaves.begin(), data.slaves.end());
  for (const std::string& camera : cameras) {
    const auto it = log->poses.find(camera);
    if (it == log->poses.end() || it->second.t_ns.empty()) return {};
    TimedTrajectory trajectory;
    trajectory.name = camera;
    trajectory.t_ns = it->second.t_ns;
    trajectory.poses = it->second.poses;
    trajectory.segment = it->second.segment;
    odometry.push_back(std::move(trajectory));
  }
  return odometry;
}

// The truth compared by the one comparison (truth_files.h): per master segment when the truth
// has trajectories and the poses are given, else from the mountings.
Status AddTruth(const std::string& path, const LogContents* log, ReportData* data) {
  std::vector<std::string> cameras = {data->final_result.master};
  cameras.insert(cameras.end(), data->slaves.begin(), data->slaves.end());
  auto truth = io::ReadTruthFiles(path, cameras);
  if (!truth) return truth.status();
  for (const std::string& slave : data->slaves) {
    if (truth->mountings.count(slave) == 0) {
      return Error{path + ": no truth for slave '" + slave + "'"};
    }
  }
  const std::vector<TimedTrajectory> odometry = OdometryOf(log, *data);
  if (!truth->trajectories.empty() && odometry.empty()) {
    data->notes.push_back("the true trajectories of " + path +
                          " are not used: no poses of every camera (RIGCAL_POSE_<camera> events "
                          "in the log, or --poses LOG)");
  }
  auto comparison = io::CompareRunWithTruth(
      data->final_result, *truth, io::TruthUnit::kAuto,
      truth->trajectories.empty() ? std::vector<TimedTrajectory>{} : odometry);
  if (!comparison) return Error{path + ": " + comparison.error()};
  data->truth = comparison->truth_master_units;
  data->notes.push_back("truth from " + path + ": " + comparison->alignment.message);
  if (!comparison->note.empty()) data->notes.push_back(comparison->note);
  if (!std::isfinite(data->metres_per_unit) && comparison->alignment.applied) {
    data->metres_per_unit = comparison->alignment.metres_per_unit;
    data->metres_source = "the master unit fitted to the truth";
  }
  return {};
}

// The config's intrinsics and, for a metric master, metres.
Status AddConfig(const std::string& path, ReportData* data) {
  auto config = io::LoadRigConfig(path);
  if (!config) return Error{config.error()};
  data->config = path;
  for (const io::CameraConfig& camera : config->cameras) {
    if (!camera.spec) continue;
    camera::CameraSpec spec = *camera.spec;
    spec.name = camera.name;
    data->intrinsics.push_back(std::move(spec));
  }
  if (!config->cameras.empty() && !data->master.empty() &&
      config->cameras.front().name != data->master) {
    return Error{path + ": the config's master is '" + config->cameras.front().name +
                 "', the result's '" + data->master + "'"};
  }
  if (!config->cameras.empty() && config->cameras.front().metric &&
      !std::isfinite(data->metres_per_unit)) {
    data->metres_per_unit = 1.0;
    data->metres_source = "metric master (" + path + ")";
    data->distance_unit = "m";
  }
  return {};
}

}  // namespace

Expected<ReportData> LoadReport(const ReportOptions& options) {
  ReportData data;
  data.input = options.input;
  std::optional<LogContents> log;
  if (internal::IsLcmLog(options.input)) {
    auto contents = internal::ReadLogContents(options.input);
    if (!contents) return contents.status();
    data.from_log = true;
    if (Status s = FillFromLog(*contents, &data); !s.ok()) return s;
    AddLogNotes(*contents, &data);
    log = std::move(*contents);
  } else {
    auto result = io::ReadResultFile(options.input);
    if (!result) {
      return Error{result.error() + " (" + options.input +
                   " is neither a result file nor an LCM log, which starts with LCM's sync "
                   "word)"};
    }
    data.final_result = std::move(*result);
    data.master = data.final_result.master;
    auto unit = io::ReadResultDistanceUnit(options.input);
    if (unit && unit->rfind("m:", 0) == 0) {
      data.distance_unit = "m";
      data.metres_per_unit = 1.0;
      data.metres_source = "C in metres (the result's provenance)";
    }
    for (const SlaveCalibration& s : data.final_result.slaves) data.slaves.push_back(s.name);
    data.notes.push_back(
        "no history in a result file: the plots over time need the LCM log of the run "
        "(RIGCAL_EXTRINSICS, RIGCAL_STATUS)");
  }

  if (!options.poses_log.empty()) {
    auto contents = internal::ReadLogContents(options.poses_log);
    if (!contents) return contents.status();
    if (contents->poses.empty()) {
      return Error{options.poses_log + ": no valid RIGCAL_POSE_<camera> event in the log"};
    }
    if (!contents->damage.empty()) data.notes.push_back(contents->damage);
    log = std::move(*contents);
    if (!data.from_log) {
      data.t0_ns = log->poses.begin()->second.t_ns.empty() ? 0 : log->poses.begin()->second.t_ns[0];
      for (const auto& [camera, poses] : log->poses) {
        if (!poses.t_ns.empty()) data.t0_ns = std::min(data.t0_ns, poses.t_ns.front());
      }
    }
  }
  const std::string pose_source = options.poses_log.empty() ? options.input : options.poses_log;
  if (log && !log->poses.empty()) {
    auto motions = internal::AnalyseMotions(log->poses, data, pose_source);
    if (motions) {
      data.motions = std::move(*motions);
    } else {
      data.notes.push_back("no per-motion residua: " + motions.error());
    }
  } else {
    data.notes.push_back(
        "no per-motion residua and measured scales: no message carries them; give the poses "
        "(RIGCAL_POSE_<camera> events in the log, or --poses LOG) to compute them");
  }

  if (!options.config.empty()) {
    if (Status s = AddConfig(options.config, &data); !s.ok()) return s;
  }
  if (!options.truth.empty()) {
    if (Status s = AddTruth(options.truth, log ? &*log : nullptr, &data); !s.ok()) return s;
  }
  return data;
}

}  // namespace rigcal::report
