#pragma once
// CalibNode: the `rigcal calib` LCM node. Receives RIGCAL_POSE_<camera> messages (VO running in
// other processes or on other computers), feeds them through SyncBuffer + RigEstimator (the
// OnlineCalibrator threads), publishes RIGCAL_EXTRINSICS and RIGCAL_STATUS at their rates, saves
// the estimator state atomically at an interval and on stop, and writes the result YAML at the
// end.
//
// Threads: Run() handles LCM on the caller's thread (receive, publish, state saves); the
// OnlineCalibrator owned by the node runs the estimator and refinement threads. Stop by setting
// the `stop` flag passed to Run (e.g. from a signal handler).

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rigcal/calib/online_calibrator.h"
#include "rigcal/calib/status.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/status_message.h"

namespace lcm {
class LCM;
}

namespace rigcal::tools {

struct CalibNodeOptions {
  // Live input: an LCM URL ("" = LCM's default, udpm://239.255.76.67:7667). Poses are received
  // and the node's messages published on it.
  std::string lcm_url;
  // Replay input instead of a live bus: an LCM log file (lcm-logger format), read as fast as
  // possible; the run ends at the end of the log. A truncated last event ends the replay with a
  // warning. Empty = live.
  std::string log_path;
  // Where to publish when replaying a log (e.g. "file:///tmp/out.log?mode=w"); empty = publish
  // nothing. Ignored for live input (the node publishes on lcm_url).
  std::string publish_url;
  std::string result_path;  // result YAML written on exit (atomically); empty = none
  std::string state_path;   // overrides the config's state.path when not empty
  bool resume = false;      // continue from the state file (ignored with a warning if unusable)
  double duration_s = 0.0;  // wall-clock limit of Run, 0 = none
  // A camera whose newest pose is older than this (wall clock) is reported VO_DEAD (live input).
  double camera_timeout_s = 5.0;
  // Seconds between status lines in the log (info level), 0 = none.
  double report_every_s = 0.0;
};

// Per-camera counters of the node (the sync buffer's drops are in SyncStats).
struct CameraInputStats {
  int64_t received = 0;  // poses accepted by the decoder
  int64_t invalid = 0;   // messages on the camera's channel rejected by validation
  int64_t last_t_ns = -1;
};

struct CalibNodeSummary {
  RigEstimate estimate;
  SyncStats sync;
  DecodeStats decode;
  std::vector<CameraInputStats> cameras;  // camera index order
  int64_t unknown_channel = 0;            // RIGCAL_POSE_* messages for cameras not in the rig
  int64_t extrinsics_published = 0;
  int64_t status_published = 0;
  int64_t state_saves = 0;
  bool resumed = false;             // state restored from the state file
  bool end_of_log = false;          // replay reached the end of the log
  std::string log_problem;          // e.g. a truncated last event; empty when the log was clean
  std::vector<std::string> errors;  // failed state/result writes, publish failures
};

class CalibNode {
 public:
  // `lcm` (optional, not owned): use this LCM instance for input and output instead of opening
  // options.lcm_url (in-process memq:// tests). It must outlive the node.
  CalibNode(RigConfig config, CalibNodeOptions options, lcm::LCM* lcm = nullptr);
  ~CalibNode();
  CalibNode(const CalibNode&) = delete;
  CalibNode& operator=(const CalibNode&) = delete;

  // Opens LCM (or the log), subscribes RIGCAL_POSE_*, restores the state when resuming.
  // The error names the URL / file. Call once before Run.
  [[nodiscard]] Status Open();

  // Runs until `stop` is set, the duration passes or the log ends; then flushes the estimator,
  // publishes a last RIGCAL_EXTRINSICS and RIGCAL_STATUS, saves the state and writes the result.
  // Call once, after Open.
  CalibNodeSummary Run(const std::atomic<bool>& stop);

  // Poses accepted by the decoder so far, all cameras (any thread).
  int64_t ReceivedPoses() const;

  // The channel handler (public for LCM's C-style callback; not part of the API).
  void HandlePose(const std::string& channel, const void* data, int64_t size);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The rig_extrinsics_t of an online estimate: the batch conversion plus the estimator's online
// flags (decalibrated, ...). Fails as RigCalibrationToLcm does.
Expected<rig_extrinsics_t> EstimateToLcm(const RigEstimate& estimate, int64_t utime);

}  // namespace rigcal::tools
