#pragma once
// OnlineCalibrator: owns the estimator thread (SyncBuffer -> RigEstimator) and the background
// refinement thread. Producers (VO threads, LCM handlers) call Push from any thread; readers
// take consistent snapshots of the estimate.

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/status.h"
#include "rigcal/calib/sync_buffer.h"

namespace rigcal {

struct OnlineOptions {
  SyncOptions sync;
  RigEstimatorOptions estimator;
  // Seconds between background non-linear window refinements (0 = none).
  double refine_period_s = 2.0;
  // The first violated constraint as "<field>: <constraint>", nested fields as "sync.<field>" and
  // "estimator.<field>".
  Status Check() const;
};

class OnlineCalibrator {
 public:
  // camera_names[0] is the master; options.sync.num_cameras is set from the names. Throws
  // InvalidOptions (a std::invalid_argument) when options.Check() fails. Starts no thread.
  OnlineCalibrator(std::vector<std::string> camera_names, OnlineOptions options);
  // Stops and joins the threads.
  ~OnlineCalibrator();
  OnlineCalibrator(const OnlineCalibrator&) = delete;
  OnlineCalibrator& operator=(const OnlineCalibrator&) = delete;

  // Starts the estimator and refinement threads. Call once.
  void Start();
  // Offers a pose (any thread, never blocks on the estimator).
  PushResult Push(const CameraPose& pose);
  // End of stream: resolves buffered sets and waits until the estimator has consumed them.
  void Flush();
  // Stops the threads (after consuming what is ready) and joins them. Idempotent.
  void Stop();

  // Runs the window refinement of every slave now, on the calling thread, and publishes it
  // when consistent (as the refinement thread does every refine_period_s). Call after Flush at
  // the end of a stream, so the final estimate is the refinement of the final window whatever
  // the refinement thread's timing was. Any thread; refinements are serialised.
  void RefineNow();

  // Consistent snapshot of the estimate (any thread).
  RigEstimate Estimate() const;
  SyncStats sync_stats() const { return sync_.stats(); }
  // The estimator's state, to continue after a restart (any thread; serialised with the
  // estimator thread). See RigEstimator::SaveState / RestoreState.
  RigEstimatorState SaveState() const;
  Status RestoreState(const RigEstimatorState& state);
  // Number of background refinements applied so far.
  int refinements_applied() const { return refinements_applied_.load(); }

 private:
  void EstimatorLoop();
  void RefinementLoop();

  std::vector<std::string> names_;
  OnlineOptions options_;
  SyncBuffer sync_;
  mutable std::mutex estimator_mutex_;
  RigEstimator estimator_;  // guarded by estimator_mutex_
  std::condition_variable consumed_;
  uint64_t sets_consumed_ = 0;  // guarded by estimator_mutex_
  std::mutex stop_mutex_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;    // guarded by stop_mutex_
  std::mutex refine_mutex_;  // serialises RefineNow
  std::atomic<int> refinements_applied_{0};
  std::thread estimator_thread_;
  std::thread refinement_thread_;
};

}  // namespace rigcal
