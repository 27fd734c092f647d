// SPDX-License-Identifier: Apache-2.0
// Building blocks of the thesis experiments: options, seeding, the parallel sample loop over a
// grid of generator settings, error statistics and the averaged Cramer-Rao bound.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <thread>
#include <utility>

#include "rigcal/calib/error_model.h"
#include "rigcal/calib/pair_selection.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/research/cramer_rao.h"
#include "rigcal/research/experiments.h"

namespace rigcal::research {
namespace {

uint64_t SplitMix64(uint64_t x) {
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

// Calls progress at every 10 % of `total` units and at the end. Thread-safe.
class ProgressMeter {
 public:
  ProgressMeter(const ExperimentProgress& progress, int64_t total)
      : progress_(progress), total_(std::max<int64_t>(total, 1)) {}

  // Any worker thread.
  void Add(int64_t units) RIGCAL_EXCLUDES(mutex_) {
    int64_t done = done_.fetch_add(units) + units;
    if (!progress_) return;
    const int decile = static_cast<int>(std::min<int64_t>(10, done * 10 / total_));
    if (decile <= reported_decile_.load()) return;
    MutexLock lock(mutex_);
    if (decile > reported_decile_.load()) {
      reported_decile_ = decile;
      progress_(std::min(done, total_), total_);
    }
  }

 private:
  const ExperimentProgress& progress_;
  const int64_t total_;
  std::atomic<int64_t> done_{0};
  Mutex mutex_;  // serialises the progress calls
  // Written only with mutex_ held; an atomic so that Add can skip the lock when the decile was
  // reported already.
  std::atomic<int> reported_decile_{0};
};

int ThreadCount(int requested) {
  if (requested > 0) return requested;
  return std::max(1u, std::thread::hardware_concurrency());
}

// The first exception of ParallelFor's workers (any worker thread keeps one).
class FirstFailure {
 public:
  void Keep(std::exception_ptr failure) RIGCAL_EXCLUDES(mutex_) {
    MutexLock lock(mutex_);
    if (!first_) first_ = std::move(failure);
  }
  // Rethrows the kept exception, if any.
  void Rethrow() RIGCAL_EXCLUDES(mutex_) {
    MutexLock lock(mutex_);
    if (first_) std::rethrow_exception(first_);
  }

 private:
  Mutex mutex_;
  std::exception_ptr first_ RIGCAL_GUARDED_BY(mutex_);
};

// body(i) for i in [0, count) on `threads` threads (dynamic assignment). The first exception of
// a worker is rethrown after all workers joined.
template <typename Body>
void ParallelFor(int64_t count, int threads, const Body& body) {
  threads = static_cast<int>(std::min<int64_t>(threads, std::max<int64_t>(count, 1)));
  std::atomic<int64_t> next{0};
  FirstFailure failure;
  auto worker = [&]() {
    try {
      for (int64_t i = next.fetch_add(1); i < count; i = next.fetch_add(1)) body(i);
    } catch (...) {
      failure.Keep(std::current_exception());
      next = count;
    }
  };
  if (threads <= 1) {
    worker();
  } else {
    std::vector<std::thread> pool;
    pool.reserve(threads);
    try {
      for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
    } catch (...) {  // no more threads: finish with the ones that started, or here
      if (pool.empty()) worker();
    }
    for (std::thread& t : pool) t.join();
  }
  failure.Rethrow();
}

// Mean, RMS and median of one error measure, ignoring non-finite values.
struct Moments {
  std::vector<double> values;
  void Add(double v) {
    if (std::isfinite(v)) values.push_back(v);
  }
  void Store(double* mean, double* rms, double* median) const {
    if (values.empty()) return;
    double sum = 0.0;
    for (double v : values) sum += v;
    *mean = sum / static_cast<double>(values.size());
    *rms = Rms(values);
    *median = Median(values);
  }
};

struct SampleOutcome {
  bool usable = false;
  CalibrationError error;
};

ErrorStats Summarize(const std::vector<SampleOutcome>& outcomes, size_t begin, size_t stride,
                     size_t count) {
  ErrorStats stats;
  Moments rot, dir, dist, scale;
  for (size_t i = 0; i < count; ++i) {
    const SampleOutcome& o = outcomes[begin + i * stride];
    if (!o.usable) {
      ++stats.failed;
      continue;
    }
    ++stats.usable;
    rot.Add(o.error.rot_deg);
    dir.Add(o.error.dir_deg);
    dist.Add(o.error.dist_pct);
    scale.Add(o.error.scale_pct);
  }
  rot.Store(&stats.rot_mean_deg, &stats.rot_rms_deg, &stats.rot_median_deg);
  dir.Store(&stats.dir_mean_deg, &stats.dir_rms_deg, &stats.dir_median_deg);
  dist.Store(&stats.dist_mean_pct, &stats.dist_rms_pct, &stats.dist_median_pct);
  scale.Store(&stats.scale_mean_pct, &stats.scale_rms_pct, &stats.scale_median_pct);
  return stats;
}

// The motions (0, k), k = 1..K, of slave 0 of a thesis sample.
std::vector<RigMotion> SinceStartMotions(const RigRecording& recording) {
  PairOptions pairs;
  pairs.policy = PairOptions::Policy::kSinceStart;
  return MotionsForSlave(recording, 0, SelectPairs(recording, pairs));
}

}  // namespace

std::string ToString(ExperimentKind kind) {
  switch (kind) {
    case ExperimentKind::kStability:
      return "stability";
    case ExperimentKind::kPoses:
      return "poses";
    case ExperimentKind::kMotionModel:
      return "motion-model";
    case ExperimentKind::kScaleModel:
      return "scale-model";
  }
  return "unknown";
}

bool ParseExperimentKind(const std::string& name, ExperimentKind* kind) {
  for (ExperimentKind k : {ExperimentKind::kStability, ExperimentKind::kPoses,
                           ExperimentKind::kMotionModel, ExperimentKind::kScaleModel}) {
    if (name == ToString(k)) {
      *kind = k;
      return true;
    }
  }
  return false;
}

std::vector<double> LinearGrid(double first, double last, double step) {
  std::vector<double> grid;
  if (!(step > 0.0) || !(last >= first)) return grid;
  const int64_t count = static_cast<int64_t>(std::floor((last - first) / step + 1e-9)) + 1;
  for (int64_t i = 0; i < count; ++i) {
    // Rounded to 1e-12 so that 0.1 steps print as 0.3, not 0.30000000000000004.
    grid.push_back(std::round((first + static_cast<double>(i) * step) * 1e12) / 1e12);
  }
  return grid;
}

Status ExperimentOptions::Check() const {
  auto grid_ok = [](const std::vector<double>& grid, double max) {
    if (grid.empty()) return false;
    for (double v : grid) {
      if (!std::isfinite(v) || v < 0.0 || v > max) return false;
    }
    return true;
  };
  if (samples < 1) return Error{"samples: must be >= 1"};
  if (threads < 0) return Error{"threads: must be >= 0 (0 = all cores)"};
  if (crb_samples < 0) return Error{"crb_samples: must be >= 0 (0 = no bound)"};
  if (partitions < 0) return Error{"partitions: must be >= 0 (0 = one per pose)"};
  if (num_poses < 2) return Error{"num_poses: must be >= 2"};
  if (!grid_ok(stability_eps_deg, 90.0)) {
    return Error{"stability_eps_deg: must be non-empty with values in [0, 90]"};
  }
  if (!std::isfinite(poses_eps_deg) || poses_eps_deg < 0.0 || poses_eps_deg > 90.0) {
    return Error{"poses_eps_deg: must be in [0, 90]"};
  }
  if (poses_min < 2) return Error{"poses_min: must be >= 2"};
  if (poses_max < poses_min) return Error{"poses_max: must be >= poses_min"};
  if (!grid_ok(model_eps_deg, 90.0)) {
    return Error{"model_eps_deg: must be non-empty with values in [0, 90]"};
  }
  if (!grid_ok(alpha_max_deg, 180.0)) {
    return Error{"alpha_max_deg: must be non-empty with values in [0, 180]"};
  }
  if (!grid_ok(max_scale_error_pct, 1e4)) {
    return Error{"max_scale_error_pct: must be non-empty with values in [0, 10000]"};
  }
  return Status::Ok();
}

BoundStats BoundStats::Scaled(double factor) const {
  BoundStats scaled = *this;
  scaled.rot_deg *= factor;
  scaled.dir_deg *= factor;
  scaled.dist_pct *= factor;
  scaled.scale_pct *= factor;
  return scaled;
}

CalibrationOptions ThesisCalibrationOptions(Method method, MotionModel motion_model,
                                            ScaleModel scale_model, int partitions) {
  CalibrationOptions options;
  options.method = method;
  options.motion_model = motion_model;
  options.scale_model = scale_model;
  options.partitions = partitions;
  options.pairs.policy = PairOptions::Policy::kSinceStart;
  options.alpha_threshold_deg = 0.0;
  options.outlier_mad_factor = 1e9;
  options.robust_loss = RobustLoss::kNone;
  options.compute_covariance = false;
  return options;
}

std::mt19937_64 SampleRng(uint64_t seed, uint64_t stream, uint64_t index) {
  uint64_t h = SplitMix64(seed);
  h = SplitMix64(h ^ SplitMix64(stream));
  h = SplitMix64(h ^ index);
  return std::mt19937_64(h);
}

std::vector<std::vector<ErrorStats>> RunGrid(const std::vector<ThesisSampleOptions>& points,
                                             const std::vector<CalibrationOptions>& variants,
                                             const ExperimentOptions& options, uint64_t stream) {
  const size_t num_samples = static_cast<size_t>(std::max(options.samples, 0));
  const size_t num_variants = variants.size();
  const int threads = ThreadCount(options.threads);
  ProgressMeter meter(options.progress,
                      static_cast<int64_t>(points.size()) * static_cast<int64_t>(num_samples));
  std::vector<std::vector<ErrorStats>> stats(points.size());
  std::vector<SampleOutcome> outcomes;  // [sample][variant]
  for (size_t p = 0; p < points.size(); ++p) {
    outcomes.assign(num_samples * num_variants, SampleOutcome{});
    const ThesisSampleOptions& point = points[p];
    ParallelFor(static_cast<int64_t>(num_samples), threads, [&](int64_t i) {
      std::mt19937_64 rng = SampleRng(options.seed, stream * 1000003ULL + p, i);
      std::vector<Similarity> truth;
      const RigRecording recording = ThesisSample(point, rng, &truth);
      const std::vector<RigMotion> motions = SinceStartMotions(recording);
      for (size_t v = 0; v < num_variants; ++v) {
        CalibrationOptions calib = variants[v];
        if (calib.scale_model == ScaleModel::kPartitions && calib.partitions <= 0) {
          calib.partitions = std::max<int>(1, static_cast<int>(motions.size()));
        }
        const SlaveCalibration result = CalibrateSlave(motions, calib);
        SampleOutcome& outcome = outcomes[static_cast<size_t>(i) * num_variants + v];
        // The thesis's experiments measure the error of every estimate a model produces,
        // including a model forced against the data (5.2, 5.3): counted when the solve produced
        // one (solved), whether or not the data support it (its state).
        outcome.usable = result.solved() && !truth.empty();
        if (!outcome.usable) continue;
        outcome.error = CompareToTruth(result.estimate, truth[0]);
        if (!result.position_observable) {
          outcome.error.dir_deg = outcome.error.dist_pct = outcome.error.trans_err = kNotAvailable;
        }
        if (result.scales.size() > 1 || result.scale_model == ScaleModel::kPartitions) {
          outcome.error.scale_pct = kNotAvailable;  // no single scale to compare
        }
      }
      meter.Add(1);
    });
    stats[p].resize(num_variants);
    for (size_t v = 0; v < num_variants; ++v) {
      stats[p][v] = Summarize(outcomes, v, num_variants, num_samples);
    }
  }
  return stats;
}

BoundStats AverageThesisBound(int num_poses, const ExperimentOptions& options) {
  BoundStats stats;
  const int count = options.crb_samples;
  if (count <= 0) return stats;
  std::vector<ThesisBound> bounds(static_cast<size_t>(count));
  constexpr uint64_t kBoundStream = 0xC4B0;
  ParallelFor(count, ThreadCount(options.threads), [&](int64_t i) {
    std::mt19937_64 rng = SampleRng(options.seed, kBoundStream + num_poses, i);
    ThesisSampleOptions sample;
    sample.num_poses = num_poses;
    sample.eps_deg = 0.0;
    std::vector<Similarity> truth;
    const RigRecording recording = ThesisSample(sample, rng, &truth);
    std::vector<Pose> master;
    for (const RigMotion& motion : SinceStartMotions(recording)) master.push_back(motion.master);
    if (truth.empty()) return;
    bounds[i] = ThesisCramerRaoBound(master, truth[0], 1.0 * kRadPerDeg);
  });
  double rot = 0.0, dir = 0.0, dist = 0.0, scale = 0.0;
  for (const ThesisBound& b : bounds) {
    if (!b.finite) {
      ++stats.degenerate;
      continue;
    }
    ++stats.geometries;
    rot += b.rot_deg * b.rot_deg;
    dir += b.dir_deg * b.dir_deg;
    dist += b.dist_pct * b.dist_pct;
    scale += b.scale_pct * b.scale_pct;
  }
  if (stats.geometries > 0) {
    const double n = stats.geometries;
    stats.rot_deg = std::sqrt(rot / n);
    stats.dir_deg = std::sqrt(dir / n);
    stats.dist_pct = std::sqrt(dist / n);
    stats.scale_pct = std::sqrt(scale / n);
  }
  return stats;
}

}  // namespace rigcal::research
