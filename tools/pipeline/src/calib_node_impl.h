#pragma once
// CalibNode::Impl, private to rigcal_pipeline:
//   calib_node.cc    construction, Open, the live loop, pose hand-over, publishing, state, result
//   log_replay.cc    the replay of a log: reading, time window, pacing, log-time timers, images
//
// Threads (calib_node.h): the LCM/reader thread runs Run; in an image replay the pose sink, the
// timers and the publishing run on the VO thread that releases a pose (one at a time, the
// PoseMerge serialises them), and the reader thread touches only the reader, the feeds and the
// replay counters until the pipeline has finished.

#include <atomic>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "frame_feed_device.h"
#include "periodic_schedule.h"
#include "rigcal/base/logging.h"
#include "rigcal/lcm/log_reader.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/calib_node.h"
#include "rigcal/pipeline/pipeline.h"

namespace rigcal::pipeline {

struct CalibNode::Impl {
  using Clock = std::chrono::steady_clock;

  io::RigConfig config;
  CalibNodeOptions options;
  lcm::CameraNames names;
  std::shared_ptr<spdlog::logger> log = ModuleLogger("tools");
  ::lcm::LCM* bus = nullptr;  // input + output for live runs (owned or external)
  std::unique_ptr<::lcm::LCM> owned_bus;
  std::unique_ptr<::lcm::LCM> output;  // replay: optional output
  OnlineCalibrator calibrator;
  lcm::MessageValidator validator;
  CalibNodeSummary summary;
  std::string state_path;
  bool opened = false;
  std::atomic<int64_t> received_total{0};  // written by the input thread, read by ReceivedPoses

  // Timers: wall clock (live) or log time (replay).
  PeriodicSchedule schedule;
  int job_extrinsics = -1, job_status = -1, job_state = -1, job_report = -1;

  // Status bookkeeping (the thread that publishes).
  std::vector<lcm::StampRate> rates;
  std::vector<Clock::time_point> last_pose_wall;  // live
  lcm::CpuMeter cpu;

  // Replay (log_replay.cc).
  std::unique_ptr<lcm::LogReader> reader;
  int64_t first_stamp_ns = -1;  // first message stamp of the log
  int64_t clock_ns = -1;        // log time: the newest stamp handed on
  Clock::time_point pace_wall_start;
  int64_t pace_stamp_start = -1;
  std::vector<FrameFeedDevice*> feeds;  // image replay; owned by `pipeline`
  // Image replay: images rejected per camera, counted by the reader, read by the status.
  std::unique_ptr<std::atomic<int64_t>[]> images_invalid;
  std::unique_ptr<Pipeline> pipeline;

  Impl(io::RigConfig c, CalibNodeOptions o);

  bool replaying() const { return !options.log_path.empty(); }
  ::lcm::LCM* Output() { return replaying() ? output.get() : bus; }
  // Index of the camera of a pose / image channel, -1 when none of the rig's.
  int CameraOfChannel(const std::string& channel, bool images) const;
  void Reject(const std::string& what);

  // calib_node.cc.
  void HandlePose(const std::string& channel, const void* data, int64_t size);
  // A decoded pose of `camera` to the calibrator (counted; log time advanced in a replay).
  void Accept(int camera, const CameraPose& pose);
  // The pose sink of an image replay (a VO thread): log time, publish the pose, Accept.
  void AcceptVoPose(const CameraPose& pose);
  template <typename Message>
  void Publish(const std::string& channel, const Message& msg, int64_t* counter);
  void RunJob(int job, int64_t utime);
  void PublishExtrinsics(const RigEstimate& estimate, int64_t utime);
  void PublishStatus(const RigEstimate& estimate, int64_t utime);
  std::vector<lcm::CameraStatusInput> CameraInputs();
  // No set reached the estimator in this run and no state was resumed.
  bool CalibratedNothing();
  // Saves the state, unless that would replace a saved state with an empty one.
  void SaveState();
  void ReportLine(const RigEstimate& estimate);
  // --resume: a state file that cannot be used is renamed aside (KeepAside), never overwritten.
  void RestoreState();
  // Flush, final refinement, last publication, state and result.
  void Finish(int64_t utime);

  // log_replay.cc.
  Status OpenLog();
  void ReplayLog(const std::atomic<bool>& stop);
  // Log time moves on to t_ns: the timers due until then run (after the estimator has caught
  // up, so what they publish does not depend on thread timing).
  void AdvanceLogTime(int64_t t_ns);
  ReplayProgress Progress() const;
};

}  // namespace rigcal::pipeline
