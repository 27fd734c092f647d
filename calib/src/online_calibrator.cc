#include "rigcal/calib/online_calibrator.h"

#include "rigcal/calib/logging.h"

namespace rigcal {
namespace {

// The options with sync.num_cameras set from the camera count, checked (InvalidOptions).
OnlineOptions Checked(OnlineOptions options, size_t cameras) {
  options.sync.num_cameras = static_cast<int>(cameras);
  RequireValid(options.Check(), "OnlineOptions");
  return options;
}

}  // namespace

Status OnlineOptions::Check() const {
  if (const Status s = sync.Check(); !s.ok()) return Error{"sync." + s.message()};
  if (const Status s = estimator.Check(); !s.ok()) return Error{"estimator." + s.message()};
  if (refine_period_s < 0.0) return Error{"refine_period_s: must be >= 0 (0 = no refinement)"};
  return Status::Ok();
}

OnlineCalibrator::OnlineCalibrator(std::vector<std::string> camera_names, OnlineOptions options)
    : names_(std::move(camera_names)),
      options_(Checked(std::move(options), names_.size())),
      sync_(options_.sync),
      estimator_(names_, options_.estimator) {}

OnlineCalibrator::~OnlineCalibrator() { Stop(); }

void OnlineCalibrator::Start() {
  estimator_thread_ = std::thread(&OnlineCalibrator::EstimatorLoop, this);
  if (options_.refine_period_s > 0.0) {
    refinement_thread_ = std::thread(&OnlineCalibrator::RefinementLoop, this);
  }
}

PushResult OnlineCalibrator::Push(const CameraPose& pose) { return sync_.Push(pose); }

void OnlineCalibrator::Flush() {
  sync_.Flush();
  const uint64_t target = sync_.stats().sets_emitted;
  MutexLock lock(estimator_mutex_);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  // Sets dropped by a full ready queue never arrive: wait for the queue to drain instead.
  while (sets_consumed_ < target && sync_.stats().ready_fill != 0) {
    if (lock.WaitUntil(consumed_, deadline) == std::cv_status::timeout) break;
  }
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

RigEstimate OnlineCalibrator::Estimate() const {
  MutexLock lock(estimator_mutex_);
  return estimator_.Estimate();
}

RigEstimatorState OnlineCalibrator::SaveState() const {
  MutexLock lock(estimator_mutex_);
  return estimator_.SaveState();
}

Status OnlineCalibrator::RestoreState(const RigEstimatorState& state) {
  MutexLock lock(estimator_mutex_);
  return estimator_.RestoreState(state);
}

void OnlineCalibrator::EstimatorLoop() {
  MatchedSet set;
  while (sync_.Pop(&set, std::chrono::milliseconds(200)) || !sync_.stopped()) {
    if (set.poses.empty()) continue;
    {
      MutexLock lock(estimator_mutex_);
      estimator_.AddSet(set.t_ns, set.poses);
      ++sets_consumed_;
    }
    consumed_.notify_all();
    set.poses.clear();
  }
  consumed_.notify_all();
}

void OnlineCalibrator::RefinementLoop() {
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
    RefineNow();
    stop_lock.Lock();
  }
}

void OnlineCalibrator::RefineNow(bool final) {
  MutexLock serial(refine_mutex_);
  for (size_t i = 0; i + 1 < names_.size(); ++i) {
    RefinementJob job;
    {
      MutexLock lock(estimator_mutex_);
      job = estimator_.MakeRefinementJob(static_cast<int>(i), final);
    }
    if (!job.start.solved() || static_cast<int>(job.motions.size()) + job.prior.motions < 10) {
      continue;
    }
    const SlaveCalibration refined = RefineWindow(job);
    MutexLock lock(estimator_mutex_);
    if (estimator_.ApplyRefinement(job, refined)) ++refinements_applied_;
  }
}

}  // namespace rigcal
