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
  std::string e;
  if (!sync.Check(&e)) return Error{"sync." + e};  // SyncOptions: bool Check(std::string*)
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
  std::unique_lock<std::mutex> lock(estimator_mutex_);
  // Sets dropped by a full ready queue never arrive: wait for the queue to drain instead.
  consumed_.wait_for(lock, std::chrono::seconds(30),
                     [&] { return sets_consumed_ >= target || sync_.stats().ready_fill == 0; });
}

void OnlineCalibrator::Stop() {
  {
    std::lock_guard<std::mutex> lock(stop_mutex_);
    stopping_ = true;
  }
  stop_cv_.notify_all();
  sync_.Stop();
  if (estimator_thread_.joinable()) estimator_thread_.join();
  if (refinement_thread_.joinable()) refinement_thread_.join();
}

RigEstimate OnlineCalibrator::Estimate() const {
  std::lock_guard<std::mutex> lock(estimator_mutex_);
  return estimator_.Estimate();
}

RigEstimatorState OnlineCalibrator::SaveState() const {
  std::lock_guard<std::mutex> lock(estimator_mutex_);
  return estimator_.SaveState();
}

Status OnlineCalibrator::RestoreState(const RigEstimatorState& state) {
  std::lock_guard<std::mutex> lock(estimator_mutex_);
  return estimator_.RestoreState(state);
}

void OnlineCalibrator::EstimatorLoop() {
  MatchedSet set;
  while (sync_.Pop(&set, std::chrono::milliseconds(200)) || !sync_.stopped()) {
    if (set.poses.empty()) continue;
    {
      std::lock_guard<std::mutex> lock(estimator_mutex_);
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
  const auto period = std::chrono::duration<double>(options_.refine_period_s);
  std::unique_lock<std::mutex> stop_lock(stop_mutex_);
  while (!stop_cv_.wait_for(stop_lock, period, [this] { return stopping_; })) {
    stop_lock.unlock();
    RefineNow();
    stop_lock.lock();
  }
}

void OnlineCalibrator::RefineNow() {
  std::lock_guard<std::mutex> serial(refine_mutex_);
  for (size_t i = 0; i + 1 < names_.size(); ++i) {
    RefinementJob job;
    {
      std::lock_guard<std::mutex> lock(estimator_mutex_);
      job = estimator_.MakeRefinementJob(static_cast<int>(i));
    }
    if (!job.start.usable() || static_cast<int>(job.motions.size()) + job.prior.motions < 10) {
      continue;
    }
    const SlaveCalibration refined = RefineWindow(job);
    std::lock_guard<std::mutex> lock(estimator_mutex_);
    if (estimator_.ApplyRefinement(job, refined)) ++refinements_applied_;
  }
}

}  // namespace rigcal
