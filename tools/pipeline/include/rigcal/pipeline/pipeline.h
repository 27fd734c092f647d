// SPDX-License-Identifier: Apache-2.0
#pragma once
// Pipeline: the live data flow of `rigcal run` (docs/architecture.md):
//
//   capture thread per device --(bounded frame queue, drop-oldest)--> VO thread per camera
//   --(CameraPose)--> OnlineCalibrator (SyncBuffer -> RigEstimator, refinement thread)
//
// One object owns and joins every thread. Capture never waits for VO in live mode: a full
// frame queue drops its oldest frame and counts it (VO backlog). In lossless mode (recorded or
// simulated sources that are not paced in real time) capture waits for room instead, and the
// poses reach the calibrator in one canonical order whatever the thread timing (PoseMerge), so
// a run is deterministic. Slaves are optional members of a sync set, so a dead slave camera leaves
// the others calibrating; a dead master stops the calibration (the status says so).
//
// Threads: the owner calls Start and Stop (stop_mutex_ serialises them); any thread calls
// Snapshot, Finished and RecordedPoses. Per camera, a capture thread (CaptureLoop) grabs frames
// into the camera's frame queue and a VO thread (VoLoop) turns them into poses and hands them to
// the calibrator (Forward, directly or through the PoseMerge, whose sink runs Forward on the VO
// thread that releases the pose). A camera's health, timings and recorded poses are guarded by
// its own mutex (Camera::mutex in pipeline.cc).

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/base/bounded_queue.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/calib/online_calibrator.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/lcm/shared_bus.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/vo/monocular_vo.h"

namespace rigcal {
class PoseMerge;
}

namespace rigcal::pipeline {

struct PipelineOptions {
  vo::VoOptions vo;
  // Frames buffered between a camera's capture and its VO thread, >= 1.
  int frame_queue_capacity = 4;
  // Capture waits for the VO instead of dropping frames (for sources not paced in real time).
  bool lossless = false;
  // Keep every pose of every camera (for evaluation against ground truth; memory grows with
  // the run length, ~100 bytes per pose).
  bool record_poses = false;
  // When set, every pose goes to this function (in the PoseMerge's canonical order when
  // lossless; on a VO thread, one call at a time when lossless) instead of to a calibrator the
  // pipeline owns: `rigcal replay` of an image log hands them to its CalibNode. The snapshot
  // then carries no sync statistics or estimate, and calibrator() must not be called.
  std::function<void(const CameraPose&)> pose_sink;
  // Success, or the first offending field and its constraint: "<field>: <constraint>"
  // ("vo.<field>: ..." for the VO's options).
  Status Check() const;
};

// Health of one camera of a running pipeline.
struct CameraHealth {
  std::string name;
  int64_t frames_captured = 0;   // frames handed over by the device
  int64_t dropped_backlog = 0;   // frames dropped because the VO fell behind
  int64_t frames_processed = 0;  // frames through the VO
  int64_t poses = 0;             // poses pushed to the calibrator
  int64_t sync_rejected = 0;     // poses the sync buffer refused (late, out of order, ...)
  vo::VoState vo_state = vo::VoState::kInitialising;
  int segment = 0;
  int relocalisations = 0;  // tracking regained against the VO's map (same segment)
  double vo_ms_median = 0.0;  // over the last 64 frames
  int64_t last_frame_t_ns = -1;
  int64_t last_pose_t_ns = -1;
  bool ended = false;  // end of stream
  bool dead = false;   // the device failed
  std::string dead_reason;
  std::string vo_message;  // why the VO is initialising or lost
};

// camera_status_t::VO_* of a camera's health (DEAD when its device failed).
int8_t CameraStatusVoState(const CameraHealth& health);
// The STATUS view of a camera's health (name, frames, backlog drops, VO state and segment, pose
// age in stream time); the caller adds fps and the drops it counts itself.
lcm::CameraStatusInput StatusInputOf(const CameraHealth& health);

struct PipelineSnapshot {
  std::vector<CameraHealth> cameras;
  SyncStats sync;
  RigEstimate estimate;
  bool finished = false;  // every camera ended or died and its frames were processed
};

// The online options of a rigcal process for `cameras` cameras: slaves are optional members of
// a set unless the config names the required ones (a dead slave must not stop the others);
// `lossless` (a source that can wait: a log, a simulation not paced in real time): back-pressure
// instead of drops and refinements on stream time (OnlineOptions), so the same input gives the
// same result bit for bit, live or replayed.
OnlineOptions ProcessOnlineOptions(OnlineOptions online, size_t cameras, bool lossless);

class Pipeline {
 public:
  // names[0] is the master; devices[i] and cameras[i] belong to names[i]. `online` are the
  // calibrator's options, completed by ProcessOnlineOptions (options.lossless). `bus`
  // (optional, not owned, must outlive the pipeline): every pose is also published on
  // RIGCAL_POSE_<camera>, from the VO threads; the process's other publishers share `bus`. Throws
  // std::invalid_argument on inconsistent arguments.
  Pipeline(std::vector<std::string> names,
           std::vector<std::unique_ptr<capture::CameraDevice>> devices,
           std::vector<std::shared_ptr<const camera::CameraModel>> cameras, OnlineOptions online,
           PipelineOptions options, lcm::SharedBus* bus = nullptr);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Starts every thread. Call once.
  void Start() RIGCAL_EXCLUDES(stop_mutex_);
  // Any thread.
  PipelineSnapshot Snapshot() const;
  // Every VO thread has ended (false before Start). Any thread.
  bool Finished() const;
  // Interrupts the devices, lets the VO threads finish the queued frames, flushes the
  // calibrator and joins every thread. Idempotent.
  void Stop() RIGCAL_EXCLUDES(stop_mutex_);

  // Every pose of camera i so far (record_poses only). Any thread.
  std::vector<CameraPose> RecordedPoses(int camera) const;
  const std::vector<std::string>& names() const { return names_; }
  OnlineCalibrator& calibrator() { return *calibrator_; }

 private:
  struct Camera;
  void CaptureLoop(int camera);
  void VoLoop(int camera);
  // Hands one pose to the calibrator (and LCM); counts a rejection.
  void Forward(const CameraPose& pose);

  std::vector<std::string> names_;
  PipelineOptions options_;
  lcm::SharedBus* bus_ = nullptr;
  std::unique_ptr<OnlineCalibrator> calibrator_;
  std::vector<std::unique_ptr<Camera>> cameras_;
  std::unique_ptr<PoseMerge> merge_;  // lossless runs only
  // VO threads not ended yet: every camera's until Start, then each VO thread counts itself
  // down. Lock-free, for Finished().
  std::atomic<int> vo_threads_running_;
  Mutex stop_mutex_;
  bool started_ RIGCAL_GUARDED_BY(stop_mutex_) = false;
  bool stopped_ RIGCAL_GUARDED_BY(stop_mutex_) = false;
};

}  // namespace rigcal::pipeline
