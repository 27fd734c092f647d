// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/online_calibrator.h"

#include <pthread.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "online/resume_check.h"
#include "rigcal/base/logging.h"

namespace rigcal {
namespace {

// The options with sync.num_cameras set from the camera count, checked (InvalidOptions).
// Lossless: the ready queue can take every set one push may complete (SyncBuffer::ReadyBound).
OnlineOptions CheckedOnlineOptions(OnlineOptions options, size_t cameras) {
  options.sync.num_cameras = static_cast<int>(cameras);
  if (options.time_offset.enabled) {
    options.sync.interpolate = true;
    // Slaves whose offset is estimated follow a restart of their clock (a given one is held);
    // a restart of the master's clock is followed by moving every slave's offset.
    const std::vector<std::optional<double>>& given = options.time_offset.given_s;
    options.sync.follow_clock_jumps.assign(cameras, false);
    if (cameras > 0) options.sync.follow_clock_jumps[0] = true;
    for (size_t c = 1; c < cameras; ++c) {
      options.sync.follow_clock_jumps[c] = given.size() < c || !given[c - 1].has_value();
    }
  }
  RequireValid(options.Check(), "OnlineOptions");
  if (options.lossless) {
    options.sync.ready_capacity = std::max(options.sync.ready_capacity, options.sync.capacity + 1);
  }
  return options;
}

constexpr auto kWaitSlice = std::chrono::milliseconds(50);

// The calling thread's name as `top -H` and /proc/<pid>/task/*/comm show it (at most 15 chars).
void NameThisThread(const char* name) {
#ifdef __linux__
  pthread_setname_np(pthread_self(), name);
#else
  (void)name;
#endif
}

}  // namespace

Status OnlineOptions::Check() const {
  if (const Status s = sync.Check(); !s.ok()) return Error{"sync." + s.message()};
  if (const Status s = estimator.Check(); !s.ok()) return Error{"estimator." + s.message()};
  if (refine_period_s < 0.0) return Error{"refine_period_s: must be >= 0 (0 = no refinement)"};
  if (time_offset.enabled) {
    if (const Status s = time_offset.Check(sync.num_cameras - 1); !s.ok()) return s;
  }
  return Status::Ok();
}

OnlineCalibrator::OnlineCalibrator(std::vector<std::string> camera_names, OnlineOptions options)
    : names_(std::move(camera_names)),
      options_(CheckedOnlineOptions(std::move(options), names_.size())),
      sync_(options_.sync),
      estimator_(names_, options_.estimator),
      resume_check_(std::make_unique<internal::ResumeCheck>()) {
  history_timing_.resize(names_.empty() ? 0 : names_.size() - 1);
  if (options_.time_offset.enabled) {
    clock_ = std::make_unique<ClockOffsetTracker>(names_, options_.time_offset);
    clock_jumps_seen_.assign(clock_->num_slaves(), 0);
    for (int i = 0; i < clock_->num_slaves(); ++i) {
      sync_.SetTimeOffset(i + 1, clock_->MatchingOffsetNs(i));
    }
  }
}

OnlineCalibrator::~OnlineCalibrator() { Stop(); }

void OnlineCalibrator::Start() {
  estimator_thread_ = std::thread(&OnlineCalibrator::EstimatorLoop, this);
  if (options_.refine_period_s > 0.0 && !options_.refine_on_stream_time) {
    refinement_thread_ = std::thread(&OnlineCalibrator::RefinementLoop, this);
  }
}

PushResult OnlineCalibrator::Push(const CameraPose& pose) {
  PushResult result;
  if (!options_.lossless) {
    result = sync_.Push(pose);
  } else {
    MutexLock serial(push_mutex_);
    WaitForRoom();
    result = sync_.Push(pose);
  }
  if (result == PushResult::kAccepted && options_.time_offset.enabled) TrackClock(pose);
  if (result == PushResult::kConsumed && resume_check_) resume_check_->Skipped(pose);
  return result;
}

void OnlineCalibrator::TrackClock(const CameraPose& pose) {
  MutexLock lock(offset_mutex_);
  // A restart of the master's clock that the SyncBuffer followed: every offset moves by its
  // step (first: a slave's jump prior below is on the master's current clock).
  bool changed = false;
  const ClockJump master = sync_.ClockJumps(0);
  if (master.count != master_jumps_seen_) {
    clock_->FollowMasterClockJump(static_cast<double>(master.offset_ns - master_step_seen_ns_) *
                                  1e-9);
    master_jumps_seen_ = master.count;
    master_step_seen_ns_ = master.offset_ns;
    changed = true;
  }
  // Restarts of slave clocks that the SyncBuffer followed: re-acquired around their step.
  for (int i = 0; i < clock_->num_slaves(); ++i) {
    const ClockJump jump = sync_.ClockJumps(i + 1);
    if (jump.count == clock_jumps_seen_[i]) continue;
    clock_jumps_seen_[i] = jump.count;
    clock_->FollowClockJump(i, static_cast<double>(jump.offset_ns) * 1e-9);
  }
  changed = clock_->Add(pose) || changed;
  if (!changed) return;
  for (int i = 0; i < clock_->num_slaves(); ++i) {
    sync_.SetTimeOffset(i + 1, clock_->MatchingOffsetNs(i), clock_jumps_seen_[i],
                        master_jumps_seen_);
  }
}

void OnlineCalibrator::WithholdUnknownClocks(MatchedSet* set) const {
  MutexLock lock(offset_mutex_);
  for (int i = 0; i < clock_->num_slaves() && i + 1 < static_cast<int>(set->poses.size()); ++i) {
    const SlaveClockOffset o = clock_->SlaveOffset(i);
    if (!o.known || set->t_ns < o.usable_from_ns) set->poses[i + 1].reset();
  }
}

void OnlineCalibrator::CancelIfStopped() {
  const std::atomic<bool>* stop = cancel_when_.load();
  if (stop != nullptr && stop->load()) CancelRefinements();
}

void OnlineCalibrator::WaitForRoom() {
  const auto limit = static_cast<uint64_t>(options_.sync.ready_capacity);
  if (sync_.ReadyBound() <= limit) return;
  MutexLock lock(estimator_mutex_);
  while (sync_.ReadyBound() > limit && !sync_.stopped()) {
    CancelIfStopped();
    lock.WaitUntil(consumed_, std::chrono::steady_clock::now() + kWaitSlice);
  }
}

void OnlineCalibrator::Drain() {
  MutexLock lock(estimator_mutex_);
  // Every set emitted so far is consumed, or was dropped (consumer_overflow, not lossless).
  while (!sync_.stopped()) {
    const SyncStats stats = sync_.stats();
    if (sets_consumed_ + stats.consumer_overflow >= stats.sets_emitted) break;
    CancelIfStopped();
    lock.WaitUntil(consumed_, std::chrono::steady_clock::now() + kWaitSlice);
  }
}

void OnlineCalibrator::Flush() {
  if (options_.lossless) {
    MutexLock serial(push_mutex_);
    WaitForRoom();
    sync_.Flush();
  } else {
    sync_.Flush();
  }
  // Every set emitted is consumed (a set popped counts once its stream-time refinement is
  // done, so that a final RefineNow after Flush is the last refinement) or dropped. Without an
  // estimator thread nothing would consume them.
  if (estimator_thread_.joinable()) Drain();
}

void OnlineCalibrator::Stop() {
  {
    MutexLock lock(stop_mutex_);
    stopping_ = true;
  }
  stop_cv_.notify_all();
  sync_.Stop();
  if (estimator_thread_.joinable()) estimator_thread_.join();
  if (refinement_thread_.joinable()) refinement_thread_.join();
}

uint64_t OnlineCalibrator::sets_consumed() const {
  MutexLock lock(estimator_mutex_);
  return sets_consumed_;
}

RigEstimate OnlineCalibrator::Estimate() const {
  RigEstimate estimate;
  {
    MutexLock lock(estimator_mutex_);
    estimate = estimator_.Estimate();
  }
  MarkUnconfirmedResume(&estimate);
  if (!options_.time_offset.enabled) return estimate;
  estimate.master_clock_jumps = static_cast<int>(sync_.ClockJumps(0).count);
  MutexLock lock(offset_mutex_);
  for (int i = 0; i < clock_->num_slaves(); ++i) {
    const SlaveClockOffset o = clock_->SlaveOffset(i);
    if (i < static_cast<int>(estimate.rig.slaves.size()) && (o.known || !o.estimated)) {
      estimate.rig.slaves[i].time_offset_s = o.offset_s;
      estimate.rig.slaves[i].time_offset_std_s = o.std_s;
    }
    if (i < static_cast<int>(estimate.online.size())) {
      SlaveOnlineState& online = estimate.online[i];
      online.clock_offset_estimated = o.estimated;
      online.clock_offset_known = o.known;
      online.clock_drift_ppm = o.drift_ppm;
      online.clock_drift_std_ppm = o.drift_std_ppm;
      online.clock_jumps = o.jumps;
    }
  }
  return estimate;
}

void OnlineCalibrator::MarkUnconfirmedResume(RigEstimate* estimate) const {
  for (size_t i = 0; i < estimate->rig.slaves.size(); ++i) {
    // An interpolated slave's poses reach the estimator at the master's instants, not as
    // received: only the master's are compared then.
    std::optional<std::string> why = resume_check_->Verdict(0);
    if (!why && !options_.sync.interpolate) why = resume_check_->Verdict(static_cast<int>(i) + 1);
    if (!why) continue;
    SlaveCalibration& s = estimate->rig.slaves[i];
    if (s.state == SlaveState::kUsable || s.state == SlaveState::kConverged) {
      s.state = SlaveState::kInitialising;
    }
    s.message = "not usable: " + *why + "; " + s.message;
  }
}

RigEstimatorState OnlineCalibrator::SaveState() const {
  RigEstimatorState state;
  {
    MutexLock lock(estimator_mutex_);
    state = estimator_.SaveState();
  }
  if (options_.time_offset.enabled) {
    MutexLock lock(offset_mutex_);
    state.clock_offsets = clock_->SaveState();
  }
  return state;
}

Status OnlineCalibrator::RestoreState(const RigEstimatorState& state) {
  if (options_.time_offset.enabled && !state.clock_offsets.empty()) {
    // Checked before the estimator takes anything: a state is restored whole or not at all.
    MutexLock lock(offset_mutex_);
    ClockOffsetTracker check(names_, options_.time_offset);
    if (const Status s = check.RestoreState(state.clock_offsets); !s.ok()) return s;
  }
  {
    MutexLock lock(estimator_mutex_);
    const Status restored = estimator_.RestoreState(state);
    if (!restored.ok()) return restored;
    // The poses the estimator took before the restart are not taken twice; those skipped are
    // checked to be the same data.
    sync_.SkipConsumed(state.consumed_t_ns);
    resume_check_->Start(names_, state.first_consumed, state.last_consumed);
  }
  if (!options_.time_offset.enabled) {
    if (!state.clock_offsets.empty()) {
      ModuleLogger("calib")->info(
          "the state holds clock offsets of free-running cameras; stamps are matched as they "
          "are now (no estimator.time_offset): not used");
    }
    return Status::Ok();
  }
  MutexLock lock(offset_mutex_);
  if (state.clock_offsets.empty()) {
    ModuleLogger("calib")->info(
        "the state has no clock offsets (cameras synchronised then, or an older state file): "
        "estimating them afresh");
    return Status::Ok();
  }
  const Status restored = clock_->RestoreState(state.clock_offsets);
  for (int i = 0; i < clock_->num_slaves(); ++i) {
    sync_.SetTimeOffset(i + 1, clock_->MatchingOffsetNs(i));
  }
  return restored;
}

void OnlineCalibrator::EstimatorLoop() {
  NameThisThread("rigcal-estimate");
  MatchedSet set;
  const bool stream_refinement = options_.refine_on_stream_time && options_.refine_period_s > 0.0;
  const auto refine_period_ns = static_cast<int64_t>(options_.refine_period_s * 1e9);
  bool refined_once = false;
  int64_t next_refine_ns = 0;
  while (sync_.Pop(&set, std::chrono::milliseconds(200)) || !sync_.stopped()) {
    if (set.poses.empty()) continue;
    if (stream_refinement && !refined_once) {
      refined_once = true;
      next_refine_ns = set.t_ns + refine_period_ns;
    }
    {
      if (options_.time_offset.enabled) WithholdUnknownClocks(&set);
      MutexLock lock(estimator_mutex_);
      // On the master's clock as it ran at the start: the estimator's time never jumps back.
      estimator_.AddSet(set.t_ns - set.master_clock_step_ns, set.poses);
    }
    // Before the set counts as consumed, so that Drain also waits for a refinement it is due.
    if (stream_refinement && set.t_ns >= next_refine_ns) {
      RefinePeriodic();
      while (next_refine_ns <= set.t_ns) next_refine_ns += refine_period_ns;
    }
    {
      MutexLock lock(estimator_mutex_);
      ++sets_consumed_;
    }
    consumed_.notify_all();
    set.poses.clear();
  }
  consumed_.notify_all();
}

void OnlineCalibrator::RefinementLoop() {
  NameThisThread("rigcal-refine");
  auto log = ModuleLogger("calib");
  const auto period = std::chrono::ceil<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options_.refine_period_s));
  MutexLock stop_lock(stop_mutex_);
  while (true) {
    // Sleeps one period unless Stop comes first (std::condition_variable::wait_for with a
    // predicate).
    const auto deadline = std::chrono::steady_clock::now() + period;
    while (!stopping_) {
      if (stop_lock.WaitUntil(stop_cv_, deadline) == std::cv_status::timeout) break;
    }
    if (stopping_) break;
    stop_lock.Unlock();
    RefinePeriodic();
    stop_lock.Lock();
  }
}

void OnlineCalibrator::RefineNow(bool final) {
  MutexLock serial(refine_mutex_);
  const PassCount pass(this);
  for (size_t i = 0; i + 1 < names_.size(); ++i) {
    RunRefinementJob(MakeRefinementJob(static_cast<int>(i), final));
  }
}

void OnlineCalibrator::RefinePeriodic() {
  if (cancel_refinements_.load()) return;
  MutexLock serial(refine_mutex_);
  const PassCount pass(this);
  for (size_t i = 0; i + 1 < names_.size() && !cancel_refinements_.load(); ++i) {
    RefinementJob job = MakeRefinementJob(static_cast<int>(i), /*final=*/false);
    job.cancel = &cancel_refinements_;
    RunRefinementJob(job);
  }
}

void OnlineCalibrator::RefineFinalBefore(std::chrono::steady_clock::time_point deadline) {
  MutexLock serial(refine_mutex_);
  const PassCount pass(this);
  for (size_t i = 0; i + 1 < names_.size(); ++i) {
    const int slave = static_cast<int>(i);
    RefinementJob job = MakeRefinementJob(slave, /*final=*/true);
    const size_t sets = job.history.t_ns.size();
    if (sets > 0) {
      const double predicted_s = PredictedHistoryRefinementSeconds(slave, sets);
      const double left_s =
          std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
      if (!(2.0 * predicted_s <= left_s)) {
        ModuleLogger("calib")->info(
            "{}: the final history refinement ({} sets, {}) left out, {:.2f} s left; the window "
            "refined instead",
            names_[i + 1], sets,
            std::isnan(predicted_s) ? std::string("none timed yet")
                                    : fmt::format("predicted {:.2f} s", predicted_s),
            left_s);
        job.history = RigRecording{};  // the window job it carries
      }
    }
    RunRefinementJob(job);
  }
}

RefinementJob OnlineCalibrator::MakeRefinementJob(int slave, bool final) const {
  MutexLock lock(estimator_mutex_);
  return estimator_.MakeRefinementJob(slave, final);
}

double OnlineCalibrator::PredictedHistoryRefinementSeconds(int slave, size_t sets) const {
  const HistoryRefinementTiming& last = history_timing_.at(static_cast<size_t>(slave));
  if (last.sets == 0) return std::numeric_limits<double>::quiet_NaN();
  return last.seconds * static_cast<double>(sets) / static_cast<double>(last.sets);
}

void OnlineCalibrator::RunRefinementJob(const RefinementJob& job) {
  if (!job.start.solved() || static_cast<int>(job.motions.size()) + job.prior.motions < 10) {
    return;
  }
  const auto started = std::chrono::steady_clock::now();
  const SlaveCalibration refined = RefineWindow(job);
  // Cancelled: ended early, neither applied nor timed.
  if (job.cancel != nullptr && job.cancel->load()) {
    ModuleLogger("calib")->info(
        "{}: the periodic {} in flight cancelled by the stop after {:.2f} s",
        names_[static_cast<size_t>(job.slave) + 1],
        job.history.t_ns.empty()
            ? std::string("window refinement")
            : fmt::format("history refinement ({} sets)", job.history.t_ns.size()),
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count());
    return;
  }
  if (!job.history.t_ns.empty()) {
    history_timing_.at(static_cast<size_t>(job.slave)) = {
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(),
        job.history.t_ns.size()};
  }
  MutexLock lock(estimator_mutex_);
  if (estimator_.ApplyRefinement(job, refined)) ++refinements_applied_;
}

}  // namespace rigcal
