// SPDX-License-Identifier: Apache-2.0
#pragma once
// OnlineCalibrator: owns the estimator thread (SyncBuffer -> RigEstimator) and the background
// refinement thread. Producers (VO threads, LCM handlers) call Push from any thread; readers
// take consistent snapshots of the estimate.
//
// Threads: the owner calls Start, Flush, Stop and RefineNow (Start/Stop from one thread);
// producers call Push; any thread calls Estimate, SerializeState, RestoreState and the
// counters. The estimator thread (EstimatorLoop) pops matched sets and adds them to the
// estimator; the refinement thread (RefinementLoop) refines every refine_period_s
// (RefinePeriodic: RefineNow, cancelled by CancelRefinements).
// estimator_mutex_ guards the estimator and is never held during a refinement;
// refine_mutex_ (serialises RefineNow) is taken before estimator_mutex_.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/calib/clock_offset_tracker.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/calib/sync_buffer.h"

namespace rigcal {
namespace internal {
class ResumeCheck;
}

struct OnlineOptions {
  SyncOptions sync;
  RigEstimatorOptions estimator;
  // Seconds between background non-linear window refinements (0 = none).
  double refine_period_s = 2.0;
  // Back-pressure instead of drops, for sources that can wait (log replay, lossless pipeline):
  // Push waits until the estimator has made room, so no matched set is lost to
  // consumer_overflow (the ready queue holds at least sync.capacity + 1 sets then).
  bool lossless = false;
  // Refinements run on the estimator thread every refine_period_s of STREAM time (set stamps)
  // instead of on a wall-clock thread, so they see the same sets in every run of the same
  // input: together with `lossless` the same pushes give the same result bit for bit.
  bool refine_on_stream_time = false;
  // Cameras that run free (time_offset.enabled): the SyncBuffer interpolates slave poses at
  // the master's instants (sync.interpolate is set) at each slave's clock offset, which a
  // ClockOffsetTracker estimates from every pushed pose (or holds at a given value). A slave
  // is left out of the sets given to the estimator until its offset is known (and while a
  // jump of it is suspected); Estimate() reports the offset and its σ per slave. A restart of
  // an estimated slave's clock is followed (sync.follow_clock_jumps is set for those slaves)
  // and its offset re-acquired around the step (ClockOffsetTracker::FollowClockJump).
  ClockOffsetOptions time_offset;
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
  // Offers a pose (any thread). Never blocks on the estimator, unless options.lossless: then it
  // waits (pushes serialised) until the ready queue has room for every set it may complete.
  PushResult Push(const CameraPose& pose) RIGCAL_EXCLUDES(push_mutex_, estimator_mutex_);
  // End of stream: resolves buffered sets and waits until the estimator has consumed them
  // (each with its stream-time refinement; no time limit) or the buffer is stopped.
  void Flush() RIGCAL_EXCLUDES(push_mutex_, estimator_mutex_);
  // Waits until the estimator has consumed every set completed so far (without resolving the
  // sets still waiting for partners, unlike Flush): Estimate() then reflects every push made
  // before the call. For publishing on stream time; any thread but the estimator thread.
  void Drain() RIGCAL_EXCLUDES(estimator_mutex_);
  // Stops the threads (after consuming what is ready) and joins them. Idempotent.
  void Stop();

  // Runs the window refinement of every slave now, on the calling thread, and publishes it
  // when consistent (as the refinement thread does every refine_period_s). Call after Flush at
  // the end of a stream, so the final estimate is the refinement of the final window whatever
  // the refinement thread's timing was. `final` (the end of a stream): the history refinement
  // even when not due (RigEstimatorOptions::history_refine_period_s). Any thread; refinements
  // are serialised.
  void RefineNow(bool final = false);
  // The end of a stream stopped early (a signal): as RefineNow(true), but a slave's history
  // refinement only where the last one's duration, scaled to the history's size now, says it
  // ends well before `deadline` (twice the prediction must fit); otherwise, or before one was
  // timed, the window refinement of its statistics (tens of ms).
  void RefineFinalBefore(std::chrono::steady_clock::time_point deadline);
  // The stream is being stopped early (a signal): the periodic refinement in flight ends at its
  // next check (CalibrationOptions::cancel; a history refinement within tenths of a second) and
  // its outcome is dropped, and no periodic refinement runs after it. RefineNow and
  // RefineFinalBefore still run in full. Any thread; call before Flush, so that neither Flush
  // nor the final refinement waits for a periodic one.
  void CancelRefinements() { cancel_refinements_.store(true); }
  // The caller's stop flag (set by a signal handler; it must outlive the calibrator): a wait for
  // the estimator thread (a lossless Push, Drain, Flush) that sees it set cancels the periodic
  // refinements, so that it ends within tenths of a second even when the estimator thread is
  // in a history refinement. Any thread.
  void CancelRefinementsWhen(const std::atomic<bool>* stop) { cancel_when_.store(stop); }

  // Consistent snapshot of the estimate (any thread). With time_offset.enabled, every slave's
  // time_offset_s / time_offset_std_s (NaN σ: given, or not estimated yet) and its online
  // clock_* fields.
  RigEstimate Estimate() const;
  SyncStats sync_stats() const { return sync_.stats(); }
  // The estimator's state, to continue after a restart (any thread; serialised with the
  // estimator thread). See RigEstimator::SaveState / RestoreState. A restored state makes the
  // sync buffer skip the poses it consumed (SyncBuffer::SkipConsumed): call before pushing.
  // With time_offset.enabled the state carries every slave's clock offset (drift, σ, jumps;
  // ClockOffsetTracker::SaveState), restored with it: matching starts at the saved offsets.
  RigEstimatorState SaveState() const;
  Status RestoreState(const RigEstimatorState& state);
  // Sets the estimator thread has consumed (added, and refined when due on stream time).
  uint64_t sets_consumed() const RIGCAL_EXCLUDES(estimator_mutex_);
  // Number of background refinements applied so far.
  int refinements_applied() const { return refinements_applied_.load(); }
  // Refinement passes (RefineNow, RefineFinalBefore, the periodic ones) begun and ended so far:
  // none is in flight while the two are equal (read `begun` first). A load test samples the
  // heap between passes, without their transient working memory.
  struct RefinementPasses {
    uint64_t begun = 0;
    uint64_t ended = 0;
  };
  RefinementPasses refinement_passes() const {
    RefinementPasses p;
    p.begun = passes_begun_.load();
    p.ended = passes_ended_.load();
    return p;
  }

 private:
  void EstimatorLoop() RIGCAL_EXCLUDES(estimator_mutex_);
  // lossless: waits until one more push cannot overflow the ready queue (or Stop).
  void WaitForRoom() RIGCAL_EXCLUDES(estimator_mutex_);
  // In a wait for the estimator thread: CancelRefinements once the CancelRefinementsWhen flag is
  // set.
  void CancelIfStopped();
  void RefinementLoop() RIGCAL_EXCLUDES(stop_mutex_);
  // The refinement of every slave the refinement thread (or, on stream time, the estimator
  // thread) runs every refine_period_s: as RefineNow(), cancelled by CancelRefinements.
  void RefinePeriodic();
  // Refines one slave's job and applies the result when consistent; times history refinements.
  void RunRefinementJob(const RefinementJob& job) RIGCAL_REQUIRES(refine_mutex_);
  RefinementJob MakeRefinementJob(int slave, bool final) const RIGCAL_EXCLUDES(estimator_mutex_);
  // The wall time of slave's history refinement on `sets` sets, predicted from the last one's
  // (linear in the sets); NaN before one was timed.
  double PredictedHistoryRefinementSeconds(int slave, size_t sets) const
      RIGCAL_REQUIRES(refine_mutex_);
  // Time offsets: feeds an accepted pose to the tracker and passes changed offsets on to the
  // SyncBuffer; leaves out of `set` the slaves whose offset is not known.
  void TrackClock(const CameraPose& pose) RIGCAL_EXCLUDES(offset_mutex_);
  void WithholdUnknownClocks(MatchedSet* set) const RIGCAL_EXCLUDES(offset_mutex_);
  // After a resume whose input is not the state's data (ResumeCheck): every slave's estimate is
  // the state's, not this input's, and not usable.
  void MarkUnconfirmedResume(RigEstimate* estimate) const;

  std::vector<std::string> names_;
  OnlineOptions options_;
  SyncBuffer sync_;
  mutable Mutex estimator_mutex_;
  RigEstimator estimator_ RIGCAL_GUARDED_BY(estimator_mutex_);
  std::condition_variable consumed_;  // signalled when the estimator thread consumed a set
  Mutex push_mutex_ RIGCAL_ACQUIRED_BEFORE(estimator_mutex_);  // serialises lossless pushes
  uint64_t sets_consumed_ RIGCAL_GUARDED_BY(estimator_mutex_) = 0;
  Mutex stop_mutex_;
  std::condition_variable stop_cv_;  // signalled by Stop
  bool stopping_ RIGCAL_GUARDED_BY(stop_mutex_) = false;
  Mutex refine_mutex_ RIGCAL_ACQUIRED_BEFORE(estimator_mutex_);  // serialises RefineNow
  // Incremented with estimator_mutex_ held; an atomic so that refinements_applied() reads it
  // without the lock.
  std::atomic<int> refinements_applied_{0};
  std::atomic<bool> cancel_refinements_{false};                 // CancelRefinements
  std::atomic<const std::atomic<bool>*> cancel_when_{nullptr};  // CancelRefinementsWhen
  std::atomic<uint64_t> passes_begun_{0};                       // refinement_passes
  std::atomic<uint64_t> passes_ended_{0};
  // Counts one refinement pass over its scope (refinement_passes).
  class PassCount {
   public:
    explicit PassCount(OnlineCalibrator* c) : c_(c) { c_->passes_begun_.fetch_add(1); }
    ~PassCount() { c_->passes_ended_.fetch_add(1); }
    PassCount(const PassCount&) = delete;
    PassCount& operator=(const PassCount&) = delete;

   private:
    OnlineCalibrator* c_;
  };
  // Per slave (sized once), the last history refinement's wall time and sets (0 sets: none yet).
  struct HistoryRefinementTiming {
    double seconds = 0.0;
    size_t sets = 0;
  };
  std::vector<HistoryRefinementTiming> history_timing_ RIGCAL_GUARDED_BY(refine_mutex_);
  mutable Mutex offset_mutex_;
  // Null unless options_.time_offset.enabled.
  std::unique_ptr<ClockOffsetTracker> clock_ RIGCAL_GUARDED_BY(offset_mutex_);
  // Per slave, the SyncBuffer's clock jumps the tracker was told of (FollowClockJump).
  std::vector<uint64_t> clock_jumps_seen_ RIGCAL_GUARDED_BY(offset_mutex_);
  // The master's clock jumps the tracker was told of (FollowMasterClockJump), and their steps'
  // sum then.
  uint64_t master_jumps_seen_ RIGCAL_GUARDED_BY(offset_mutex_) = 0;
  int64_t master_step_seen_ns_ RIGCAL_GUARDED_BY(offset_mutex_) = 0;
  // After RestoreState: whether the skipped poses are the state's own data.
  std::unique_ptr<internal::ResumeCheck> resume_check_;
  std::thread estimator_thread_;
  std::thread refinement_thread_;
};

}  // namespace rigcal
