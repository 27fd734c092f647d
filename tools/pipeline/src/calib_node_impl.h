// SPDX-License-Identifier: Apache-2.0
#pragma once
// CalibNode::Impl, private to rigcal_pipeline:
//   calib_node.cc     construction, Open, the bus loop, pose hand-over, publishing, result
//   node_state.cc     state saves and --resume
//   log_replay.cc     the replay of a log: reading, time window, pacing, log-time timers, images
//   capture_input.cc  live capture: the config's source through the pipeline, the capture loop
//
// Threads (calib_node.h): the LCM/reader/capture-owner thread runs Run; in an image replay and a
// lossless capture the pose sink, the timers and the publishing run on the VO thread that
// releases a pose (one at a time, the PoseMerge serialises them), and Run's thread touches only
// the reader, the feeds and the replay counters until the pipeline has finished. In a live
// capture every VO thread runs the pose sink for its own camera (per-camera counters) and Run's
// thread the timers; output_mutex serialises what they publish and the errors they record.

#include <atomic>
#include <chrono>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "flow_watch.h"
#include "frame_feed_device.h"
#include "periodic_schedule.h"
#include "published_file_check.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/lcm/log_reader.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/calib_node.h"
#include "rigcal/pipeline/capture_loops.h"
#include "rigcal/pipeline/capture_sources.h"
#include "rigcal/pipeline/log_recorder.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/pipeline/replay_frame_order.h"
#include "rigcal/pipeline/replay_pacer.h"

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
  // A file:// output: the bytes it must hold, checked when it is closed (CloseOutput).
  std::optional<PublishedFileCheck> published_file RIGCAL_GUARDED_BY(output_mutex);
  // Built with the node, or by OpenCapture once the source says whether it is lossless.
  std::unique_ptr<OnlineCalibrator> calibrator;
  lcm::MessageValidator validator;
  CalibNodeSummary summary;
  std::string state_path;
  // The permission bits of a state file this run creates: a rejected state's (set aside by
  // --resume), else the default.
  unsigned state_new_file_mode = io::kNewFileMode;
  bool opened = false;
  std::atomic<int64_t> received_total{0};  // written by the input thread, read by ReceivedPoses

  // Timers: wall clock (live) or log time (replay).
  PeriodicSchedule schedule;
  int job_extrinsics = -1, job_status = -1, job_state = -1, job_report = -1;
  // The config's publish / state periods and the status lines as jobs of `schedule`.
  void AddJobs();

  // Status bookkeeping (the thread that publishes).
  std::vector<lcm::StampRate> rates;
  std::vector<Clock::time_point> last_pose_wall;  // live
  lcm::CpuMeter cpu;

  // Replay (log_replay.cc).
  std::unique_ptr<lcm::LogReader> reader;
  int64_t first_stamp_ns = -1;   // first message stamp of the log
  int64_t clock_ns = -1;         // log time: the newest stamp handed on
  ReplayPacer pacer;             // the log time of --from/--to and --speed, kept from glitches
  bool pacer_in_glitch = false;  // a burst of stamps far from the log time is being reported
  std::vector<FrameFeedDevice*> feeds;  // image replay; owned by `pipeline`
  // Image replay: images rejected per camera, counted by the reader, read by the status.
  std::unique_ptr<std::atomic<int64_t>[]> images_invalid;
  std::unique_ptr<ReplayFrameOrder> frame_order;  // image replay: frames in stamp order
  std::unique_ptr<Pipeline> pipeline;

  // Live capture (capture_input.cc).
  std::unique_ptr<CaptureSources> sources;
  bool lossless_capture = false;  // the source waits for the VO: timers on pose stamps
  // Resumed with our own VO: its segments restart at 0, so every camera's segment ids are moved
  // past the saved ones (a VO restart is a new scale segment). Empty: none.
  std::vector<int> segment_offset;
  // `rigcal record`: the log every frame is tapped into (with the poses and estimates), and the
  // capture threads when there is no VO (record_no_vo).
  std::unique_ptr<LogRecorder> recorder;
  std::unique_ptr<CaptureLoops> capture_loops;
  bool trigger_failure_told = false;  // the trigger link's failure was logged
  bool flow_healthy = true;           // FlowWatch's verdict at the last pass

  // Serialises publishing and error recording between the VO threads and Run's thread.
  Mutex output_mutex;
  std::vector<std::string> errors RIGCAL_GUARDED_BY(output_mutex);

  Impl(io::RigConfig c, CalibNodeOptions o);

  bool replaying() const { return !options.log_path.empty(); }
  bool capturing() const { return options.capture; }
  // Timers on stream time (pose / log stamps) rather than the wall clock of a live bus.
  bool stream_timers() const { return replaying() || lossless_capture; }
  // Live bus: the input bus; a replay or a capture: the output (or a bus given to the node).
  ::lcm::LCM* Output() { return replaying() || bus == nullptr ? output.get() : bus; }
  // Records an error of the run (any thread) and logs it.
  void AddError(const std::string& error) RIGCAL_EXCLUDES(output_mutex);
  // Index of the camera of a pose / image channel, -1 when none of the rig's.
  int CameraOfChannel(const std::string& channel, bool images) const;
  void Reject(const std::string& what);

  // calib_node.cc.
  void HandlePose(const std::string& channel, const void* data, int64_t size);
  // A decoded pose of `camera` to the calibrator (counted). True when the calibrator took it.
  bool Accept(int camera, const CameraPose& pose);
  // A pose on log time (a replay): the timers due until its stamp, then Accept; a stamp that
  // leaps ahead of the log clock (IsLeap) is accepted first and moves the clock only when the
  // calibrator took it, so a rejected glitch (a stamp at INT64_MAX) never moves any clock.
  void AcceptOnLogTime(int camera, const CameraPose& pose);
  // More than the SyncBuffer's smallest glitch horizon (2 s) ahead of the log clock.
  bool IsLeap(int64_t t_ns) const;
  // The pose sink of an image replay (a VO thread): log time, publish the pose, Accept (log time
  // after it for a leap, as AcceptOnLogTime).
  void AcceptVoPose(const CameraPose& pose);
  template <typename Message>
  // Publishes on Output(); `record`: also into the recording (a pose, an estimate).
  void Publish(const std::string& channel, const Message& msg, int64_t* counter,
               bool record = false);
  void RunJob(int job, int64_t utime);
  void PublishExtrinsics(const RigEstimate& estimate, int64_t utime);
  void PublishStatus(const RigEstimate& estimate, int64_t utime);
  std::vector<lcm::CameraStatusInput> CameraInputs();
  // No set reached the estimator in this run and no state was resumed.
  bool CalibratedNothing();
  // Saves the state, unless that would replace a saved state with an empty one.
  void SaveState();
  // At the end: how many state saves failed (an error when the final one did).
  void ReportStateSaves();
  void ReportLine(const RigEstimate& estimate);
  // Ok, or the error naming the state path when it is there but not a regular file (a directory,
  // symbolic link, device, FIFO): rigcal neither reads, moves nor replaces it.
  Status CheckStatePath() const;
  // --resume: a state file that cannot be used is renamed aside (KeepAside), never overwritten.
  void RestoreState();
  // After the last publication: the output closed and, for a file:// URL, its file checked (an
  // error naming the file when it does not hold everything published).
  void CloseOutput() RIGCAL_EXCLUDES(output_mutex);
  // Flush, final refinement (not when `interrupted`: stopped by a signal, so the run ends
  // promptly), last publication, state and result.
  void Finish(int64_t utime, bool interrupted);
  // Moves pose segments past the resumed state's (our own VO restarted).
  void SetSegmentOffsets(const RigEstimatorState& state);

  // capture_input.cc.
  Status OpenCapture();
  void RunCapture(const std::atomic<bool>& stop);
  // Poses from LCM until `stop` or options.duration_s, then Finish.
  void RunLcm(const std::atomic<bool>& stop);
  // The recorder tapped into every device (options.record_path); the devices without VO go to
  // CaptureLoops.
  Status OpenRecording(std::vector<std::unique_ptr<capture::CameraDevice>>* devices);
  // One pass of the capture loop at now_ns: a live source's timers, the trigger's health, the
  // recording's progress, the watchdog when frames flow. False: stop (the disk failed).
  bool CapturePass(int64_t now_ns, FlowWatch* flow);
  // Every camera ended or died (through its VO, or its capture loop without VO).
  bool CaptureFinished() const;
  // The capture's threads stopped and joined: the cameras (and VO), then the trigger.
  void StopCapture();
  // End-of-run reports of the devices, the trigger, evaluation and pose / truth files.
  void FinishCapture();

  // log_replay.cc.
  Status OpenLog();
  void ReplayLog(const std::atomic<bool>& stop);
  bool OrderAndFeed(capture::Frame frame, const std::atomic<bool>& stop);
  bool FeedInOrder(std::vector<capture::Frame> frames, const std::atomic<bool>& stop);
  void FeedRest(std::vector<capture::Frame> rest, const std::atomic<bool>& stop);
  // One event of the log for the replay: a frame of a camera or a pose, at its stamp.
  struct ReplayItem {
    int camera = -1;
    int64_t t_ns = 0;
    std::optional<CameraPose> pose;
    std::optional<capture::Frame> frame;
  };
  bool ReadReplayEvent(lcm::LogEvent* event);
  bool DecodeReplayEvent(const lcm::LogEvent& event, ReplayItem* item);
  // Takes the item's stamp into the pacer (warning once per burst of stamps far from the log
  // time); returns the stamp that decides --from / --to: its own, or the pacer's log time when
  // it is a glitch.
  int64_t PacerObserve(const ReplayItem& item);
  // Waits until the wall clock reaches the pacer's log time at options.replay.speed (no wait
  // when 0; at most the pacer's cap / speed; never past a stop).
  void PaceReplay(const std::atomic<bool>& stop);
  // Log time moves on to t_ns: the timers due until then run (after the estimator has caught
  // up, so what they publish does not depend on thread timing).
  void AdvanceLogTime(int64_t t_ns);
  ReplayProgress Progress() const;
};

}  // namespace rigcal::pipeline
