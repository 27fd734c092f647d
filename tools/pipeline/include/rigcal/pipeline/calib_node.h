// SPDX-License-Identifier: Apache-2.0
#pragma once
// CalibNode: the one owner of a running rig (`rigcal run`, `calib`, `replay`;
// docs/architecture.md). Its input is one of: poses on a bus, an LCM log, or live capture from the
// config's source.
//
// Bus (`rigcal calib`): receives RIGCAL_POSE_<camera>
// messages (VO running in other processes or on other computers), feeds them through SyncBuffer +
// RigEstimator (the OnlineCalibrator threads), publishes RIGCAL_EXTRINSICS and RIGCAL_STATUS at
// their rates, saves the estimator state atomically at an interval and on stop, and writes the
// result YAML at the end.
//
// Replay (log_path set): the log (lcm-logger format, read by LogReader) runs through the same
// node. A log with RIGCAL_IMAGE_<camera> images of the rig's cameras (unless replay.poses_only)
// runs through the live pipeline instead, images -> VO per camera -> sync -> estimator (Pipeline
// with FrameFeedDevices), and its pose channels are ignored. A replay loses nothing: the reader
// waits for the VO and the estimator (back-pressure, ProcessOnlineOptions lossless), so the same
// log gives the same result bit for bit, and the same result as the live run it was recorded
// from whenever that run dropped nothing. Every timer (publish, status, state save, status
// line, refinement) runs on LOG time, the newest message stamp (t_ns) read, so the published
// messages (utime = log time) hold the whole history of the estimate. A damaged log is replayed
// up to the damage (log_problem names the byte offset).
//
// Capture (options.capture, `rigcal run`): the config's `source:` is opened (its trigger
// generator first), the devices run through the live Pipeline (capture -> VO per camera) whose
// pose sink feeds the node's estimator; the node publishes the poses, RIGCAL_EXTRINSICS and
// RIGCAL_STATUS on publish_url, saves the state on the same schedule and stops the cameras, then
// the trigger that exposes them, then the estimator. A live source's timers run on
// CLOCK_MONOTONIC (the clock of its frame stamps), a lossless one's (a simulation not paced in
// real time, image folders) on the pose stamps, as a replay's. A resumed capture moves the VO's
// scale segments past the saved ones (the restarted VO is a new scale segment).
//
// Threads: Run() handles LCM (or reads the log) on the caller's thread; the OnlineCalibrator
// owned by the node runs the estimator (and, live, the refinement) thread; an image replay adds
// the pipeline's capture and VO threads, and then the publishing runs on the VO thread that
// hands over the poses. Stop by setting the `stop` flag passed to Run (e.g. from a signal
// handler).

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/calib/online_calibrator.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/log_recorder.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/pipeline/run_evaluation.h"

namespace lcm {
class LCM;
}

namespace rigcal::pipeline {

// How a log is replayed.
struct ReplayOptions {
  // Pace by log time at this multiple of real time; 0 = as fast as possible (default).
  double speed = 0.0;
  // Replay only log time [from_s, to_s] after the first message stamp; to_s < 0 = to the end.
  double from_s = 0.0;
  double to_s = -1.0;
  // Ignore image channels: replay the pose channels even when the log has images.
  bool poses_only = false;
  // An event longer than this is damage (rejected before any allocation).
  int64_t max_event_bytes = int64_t{64} << 20;
  // Image replay: frames buffered per camera between the log reader and the pipeline.
  int frame_feed_capacity = 64;
  // Image replay: image data held to feed the cameras' frames in stamp order when one camera's
  // frames are ahead of another's in the file (ReplayFrameOrder); beyond it a camera without
  // frames is taken as stopped up to the frames fed, and its frames that come later are late.
  double frame_order_max_mb = 256.0;
  // Success, or the first offending field: "<field>: <constraint>".
  Status Check() const;
};

// Where a replay stands; handed to CalibNodeOptions::on_progress.
struct ReplayProgress {
  int64_t bytes_read = 0;   // of the log
  int64_t log_bytes = 0;    // the log's size
  double log_time_s = 0.0;  // log time since the first message stamp
  uint64_t sets = 0;        // sets the estimator has received
  bool done = false;        // the last call, after the result
};

struct CalibNodeOptions {
  // Live input: an LCM URL ("" = LCM's default, udpm://239.255.76.67:7667). Poses are received
  // and the node's messages published on it.
  std::string lcm_url;
  // Allow an lcm_url that reaches other hosts (bus_exposure.h); otherwise Open() refuses it.
  bool lcm_network = false;
  // Replay input instead of a live bus: an LCM log file (lcm-logger format), read as fast as
  // possible; the run ends at the end of the log. A truncated last event ends the replay with a
  // warning. Empty = live.
  std::string log_path;
  // Where to publish when replaying a log (e.g. "file:///tmp/out.log?mode=w"); empty = publish
  // nothing. Ignored for live input (the node publishes on lcm_url).
  std::string publish_url;
  ReplayOptions replay;
  // Replay: called on Run's thread about every progress_every_s of wall time, and once at the end.
  std::function<void(const ReplayProgress&)> on_progress;
  double progress_every_s = 0.2;
  // Live input: called on Run's thread after every pass of its receive loop (at least every
  // 50 ms while the loop is healthy): the service watchdog (rigcal calib under systemd). A
  // capture calls it only while every camera delivered a frame and the estimator took a set
  // within camera_timeout_s (a stalled camera starves the watchdog).
  std::function<void()> on_tick;
  // Capture input instead of a bus or a log: the config's `source:` (see above). Publishes on
  // publish_url (empty = nothing), which must stay on this host unless lcm_network.
  bool capture = false;
  bool fast = false;      // capture: a simulated source not paced in real time (lossless)
  std::string poses_dir;  // capture: every VO pose to DIR/<camera>.txt at the end
  std::string truth_dir;  // capture, simulated source: its ground truth (TUM, truth.yaml)
  bool evaluate = false;  // capture, simulated source: the errors against its truth
  // Capture: record every frame (RIGCAL_IMAGE_<camera>), the VO poses and RIGCAL_EXTRINSICS into
  // this LCM log (`rigcal record`; LogRecorder); empty = no recording. `recorder.lossless` is
  // set from the source.
  std::string record_path;
  RecorderOptions recorder;
  bool record_no_vo = false;  // record the images only: no VO, no estimator input
  // Recording: called on Run's thread after every pass of the capture loop (about every 20 ms).
  std::function<void(const RecorderStats&)> on_recording;
  std::string result_path;  // result YAML written on exit (atomically); empty = none
  // Appended to the result YAML: where it came from (the `provenance:` block of
  // io::ProvenanceToYaml); empty = nothing.
  std::string result_provenance;
  std::string state_path;   // overrides the config's state.path when not empty
  bool resume = false;      // continue from the state file (ignored with a warning if unusable)
  double duration_s = 0.0;  // wall-clock limit of Run, 0 = none (live input)
  // A camera whose newest pose is older than this (wall clock) is reported VO_DEAD (live input).
  double camera_timeout_s = 5.0;
  // Seconds between status lines in the log (info level; log time in a replay), 0 = none.
  double report_every_s = 0.0;
};

// Per-camera counters of the node (the sync buffer's drops are in SyncStats).
struct CameraInputStats {
  int64_t received = 0;  // poses accepted by the decoder (image replay: poses from the VO)
  int64_t invalid = 0;   // messages on the camera's channel rejected by validation
  int64_t last_t_ns = -1;
  int32_t last_segment = -1;  // scale segment of the newest pose
  int64_t images = 0;         // image replay: frames handed to the camera's VO
  // Image replay: frames stamped before frames of the other cameras fed long before them
  // (more than the replay's frame_order_max_mb behind in the file), dropped.
  int64_t late_frames = 0;
  int64_t sync_rejected = 0;  // poses the sync buffer refused (late, out of order, ...)
};

struct CalibNodeSummary {
  RigEstimate estimate;
  SyncStats sync;
  lcm::DecodeStats decode;
  std::vector<CameraInputStats> cameras;  // camera index order
  int64_t unknown_channel = 0;            // RIGCAL_POSE_* messages for cameras not in the rig
  // Replay: events on channels the replay does not use (other channels, the image channels of
  // a pose replay, the pose channels of an image replay, rigcal's own outputs), per channel.
  std::map<std::string, int64_t> skipped_channels;
  bool image_replay = false;  // the log was replayed from its images through VO
  int64_t log_events = 0;     // events read from the log
  double log_span_s = 0.0;    // log time replayed (newest minus first message stamp)
  int64_t extrinsics_published = 0;
  int64_t status_published = 0;
  // The output did not take everything published (a file:// log that came out short: disk full,
  // write failed); the error is in `errors`.
  bool publish_failed = false;
  int64_t state_saves = 0;
  // State saves that failed (a full disk fails every one): the first is in `errors`, the rest
  // only counted; each is retried at the next save interval, never sooner.
  int64_t state_save_failures = 0;
  bool state_last_save_failed = false;  // the run's last save (its final state) failed
  bool resumed = false;                 // state restored from the state file
  std::string rejected_state;           // --resume rejected the state file: where it was kept
  bool result_written = false;          // the result file was written
  // Calibrated nothing: the existing state / result files left as they were.
  std::vector<std::string> kept_files;
  bool end_of_log = false;          // replay reached the end of the log
  std::string log_problem;          // e.g. a truncated last event; empty when the log was clean
  std::vector<std::string> errors;  // failed state/result writes, publish failures
  // Capture: every camera's health at the end, the end-of-run lines of the devices and the
  // trigger ("camera 'cam0': 95 images listed in ..."), and the errors against a simulated
  // source's truth (options.evaluate).
  std::vector<CameraHealth> camera_health;
  std::vector<std::string> capture_report;
  std::optional<RunEvaluation> evaluation;
  // Recording: what was written, and the recorder's final status (empty when it closed well).
  std::optional<RecorderStats> recording;
  std::string recording_error;
};

class CalibNode {
 public:
  // `lcm` (optional, not owned): use this LCM instance for input and output instead of opening
  // options.lcm_url (in-process memq:// tests). It must outlive the node.
  CalibNode(io::RigConfig config, CalibNodeOptions options, ::lcm::LCM* lcm = nullptr);
  ~CalibNode();
  CalibNode(const CalibNode&) = delete;
  CalibNode& operator=(const CalibNode&) = delete;

  // Opens LCM (or the log: a log with images builds the pipeline from the config's camera
  // models), subscribes RIGCAL_POSE_*, restores the state when resuming. The error names the
  // URL / file / camera. Call once before Run.
  [[nodiscard]] Status Open();

  // Runs until `stop` is set, the duration passes or the log ends; then flushes the estimator,
  // publishes a last RIGCAL_EXTRINSICS and RIGCAL_STATUS, saves the state and writes the result.
  // Call once, after Open.
  CalibNodeSummary Run(const std::atomic<bool>& stop);

  // Poses accepted by the decoder so far, all cameras (any thread).
  int64_t ReceivedPoses() const;
  // The estimator's refinement passes begun and ended so far (any thread, after Open;
  // OnlineCalibrator::refinement_passes): none in flight while they are equal.
  OnlineCalibrator::RefinementPasses RefinementPasses() const;

  // The channel handler (public for LCM's C-style callback; not part of the API).
  void HandlePose(const std::string& channel, const void* data, int64_t size);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigcal::pipeline
