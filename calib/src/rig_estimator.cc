#include "rigcal/calib/rig_estimator.h"

#include <spdlog/fmt/fmt.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "linear_solvers.h"
#include "model_selection.h"
#include "motion_data.h"
#include "motion_statistics.h"
#include "refinement.h"
#include "rigcal/calib/logging.h"
#include "rigcal/calib/quaternion.h"
#include "rotation_blocks.h"
#include "statistics_prior.h"

namespace rigcal {
namespace {

using internal::MotionData;
using internal::MotionStatistics;

struct Keyframe {
  int64_t t_ns = 0;
  Pose master;
  Pose slave;
  int segment = 0;
};

struct WindowEntry {
  RigMotion motion;
  double weight = 1.0;        // its weight in the statistics when it was added
  internal::MotionData data;  // as added (signs aligned)
  double log_decay = 0.0;     // the slave's cumulative log forgetting factor when it was added
};

// Running mean of a squared quantity over roughly the last 50 samples.
struct RunningVariance {
  double value = 0.0;
  int count = 0;
  void Add(double sq) {
    ++count;
    const double alpha = 1.0 / std::min(count, 50);
    value += alpha * (sq - value);
  }
};

// How many pairs share each error, on average: overlapping pairs (every keyframe pairs with
// one several keyframes back) share the odometry drift between their ends, so the linear
// solution's σ, which takes the motions as independent, is optimistic by the square root of
// this. Drift makes the angle-invariant variance grow with the span: its ratio between the
// pairs and the consecutive-keyframe motions measures the sharing, between 1 (errors of the
// poses alone, shared by the two pairs at a pose) and the mean span of the pairs in keyframes
// (pure drift).
internal::RotationBlocks MakeRotationBlocks(const RigEstimatorOptions& o) {
  return internal::RotationBlocks(std::max<int64_t>(1, std::llround(o.sigma_block_s * 1e9)),
                                  o.sigma_blocks);
}

double OverlapFactor(const RunningVariance& pairs, const RunningVariance& consecutive,
                     const RunningVariance& span) {
  if (pairs.count == 0 || consecutive.count == 0 || !(consecutive.value > 0.0)) return 1.0;
  return std::clamp(pairs.value / consecutive.value, 1.0, std::max(1.0, span.value));
}

double Forget(int64_t dt_ns, double half_life_s) {
  if (half_life_s <= 0.0 || dt_ns <= 0) return 1.0;
  return std::pow(0.5, static_cast<double>(dt_ns) * 1e-9 / half_life_s);
}

uint64_t Fnv1a(const std::string& s) {
  uint64_t h = 1469598103934665603ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

// The motion model of a slave (thesis 5.2): rotating once a formed motion rotated by the
// equal-error boundary at the rotation noise measured so far (model_selection.h).
struct MotionModelChoice {
  bool rotating = false;
  double noise_deg = 0.0;     // running RMS of the master-minus-slave rotation angle difference
  double boundary_deg = 0.0;  // translational below this largest rotation
};

// The equal-error boundary at the running angle-invariant variance `angle_var_deg2` (deg^2,
// from `samples` motions): the fixed alpha_maxrot until gate_after_motions motions measured it.
double TranslationalBelowDeg(const RigEstimatorOptions& o, double angle_var_deg2, int samples) {
  if (o.alpha_maxrot_noise_deg <= 0.0 || samples < o.gate_after_motions) {
    return std::max(o.alpha_maxrot_deg, o.pair_min_angle_deg);
  }
  return internal::TranslationalBelowDeg(o.alpha_maxrot_deg, o.alpha_maxrot_noise_deg,
                                         std::sqrt(std::max(angle_var_deg2, 0.0)),
                                         o.pair_min_angle_deg);
}

// Linear solution of one set of statistics, in the batch result schema, in the motion model
// `choice`. `general` is the hysteresis state of a rotating rig (true: the general model was
// chosen last time); it is updated when not null.
SlaveCalibration SolveStatistics(const MotionStatistics& stats, const RigEstimatorOptions& opt,
                                 const std::optional<Similarity>& nominal, int current_segment,
                                 const MotionModelChoice& choice, bool* general) {
  SlaveCalibration r;
  r.motions.used = stats.motions();
  r.observability.max_rotation_deg = stats.max_rotation() * kDegPerRad;
  if (stats.motions() < 2 || stats.weight() <= 0.0) {
    r.termination = Termination::kInsufficientMotion;
    r.message = "initialising: " + std::to_string(stats.motions()) + " motions so far";
    return r;
  }
  const bool translational = !choice.rotating;
  r.motion_model = translational ? MotionModel::kTranslational : MotionModel::kGeneral;
  std::map<int, double> scales;
  bool ok = true;
  if (translational) {
    r.estimate.q = stats.SolveTranslationalRotation();
    scales = stats.SolveTranslationalScales();
    // Infinite when the translations leave a rotation undetermined (driving straight).
    r.rot_std_deg = stats.TranslationalRotationStd(r.estimate.q) * kDegPerRad;
    r.position_observable = false;
    r.unobservable = {Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
    if (nominal) r.estimate.C = nominal->C;
  } else {
    internal::ModelSelectionOptions select;
    select.planar_axis_spread_deg = opt.planar_axis_spread_deg;
    select.min_tilt_snr = opt.min_tilt_snr;
    select.max_axis_std_ratio = opt.max_axis_std_ratio;
    select.general_axis_spread_deg = opt.general_axis_spread_deg;
    // Hysteresis: stay general unless clearly planar, once the figures rest on enough motions
    // (the first few motions' tilt SNR is a ratio of a handful of noise samples).
    if (general != nullptr && *general && stats.motions() >= opt.converged_min_motions) {
      select.min_tilt_snr /= opt.planar_hysteresis;
      select.max_axis_std_ratio *= opt.planar_hysteresis;
    }
    internal::AxisPrior prior;
    if (nominal) {
      prior.given = true;
      prior.nominal_C = nominal->C;
      prior.sigma = opt.nominal_sigma;
    }
    const internal::RotatingSolution sol =
        internal::SolveRotating(stats, MotionModel::kAuto, select, prior);
    if (general != nullptr) *general = sol.model == MotionModel::kGeneral;
    r.motion_model = sol.model;
    r.observability = sol.observability;
    r.estimate.q = sol.q;
    r.estimate.C = sol.C;
    scales = sol.scales;
    r.rot_std_deg = sol.rot_std_deg;
    r.pos_std = sol.cov_C.diagonal().cwiseMax(0.0).cwiseSqrt();
    r.axis_offset_std = sol.axis_std;
    if (sol.model == MotionModel::kPlanar) {
      r.unobservable.push_back(r.observability.planar_axis);
      r.unobservable_from_prior = sol.axis_from_prior;
    }
    r.message = sol.why;
    ok = sol.ok;
    if (!ok && nominal) r.estimate.C = nominal->C;
  }
  r.observability.rotation_noise_deg = choice.noise_deg;
  r.observability.translational_below_deg = choice.boundary_deg;
  for (const auto& [id, v] : stats.closed_scales()) {
    SegmentScale s;
    s.segment = id;
    s.scale = v;
    r.scales.push_back(s);
  }
  for (const auto& [id, v] : scales) {
    SegmentScale s;
    s.segment = id;
    s.scale = v;
    r.scales.push_back(s);
  }
  std::sort(r.scales.begin(), r.scales.end(),
            [](const SegmentScale& a, const SegmentScale& b) { return a.segment < b.segment; });
  r.estimate.scale = 1.0;
  for (const auto& s : r.scales) {
    if (s.segment == current_segment) r.estimate.scale = s.scale;
  }
  r.scale_model = r.scales.size() > 1 ? ScaleModel::kSegments : ScaleModel::kFixed;
  const bool finite = r.estimate.q.coeffs().allFinite() && r.estimate.C.allFinite() &&
                      std::isfinite(r.estimate.scale);
  r.termination = ok && finite ? Termination::kConverged : Termination::kDegenerate;
  return r;
}

}  // namespace

struct RigEstimator::Slave {
  std::deque<Keyframe> keyframes;
  MotionStatistics long_stats;
  MotionStatistics short_stats;
  int64_t last_decay_ns = -1;
  RunningVariance angle_var, rot_var, pos_var, ci_sq;
  MotionCounts counts;
  SlaveOnlineState online;
  std::deque<WindowEntry> window;
  // The long statistics minus the window's motions: what the window refinement's prior is
  // made of (long_stats == outside + window, decayed alike).
  MotionStatistics outside;
  double log_decay = 0.0;   // sum of the log forgetting factors applied to long_stats
  SlaveCalibration linear;  // latest linear solution of the long statistics
  std::optional<SlaveCalibration> refined;
  int disagreements = 0;
  int stable = 0;
  bool general = false;            // some motion rotated by the boundary: a rotating rig
  bool general_model = false;      // rotating rig: the general (not planar) model, with hysteresis
  int accepted_in_model = 0;       // accepted motions since the motion model last changed
  int64_t model_changed_ns = -1;   // stream time of the last change of the motion model
  int gate_rejections_in_row = 0;  // consecutive motions rejected by the residual gates
  // Drift: the angle-invariant variance of the consecutive-keyframe motion ending at each new
  // keyframe (compared with angle_var, that of the pairs) and the span of the pairs in
  // keyframes; overlapping pairs share their drift (see OverlapFactor).
  RunningVariance consecutive_angle_var, pair_span;
  // The long statistics' rotation information in time blocks (cluster-robust rotation σ).
  internal::RotationBlocks rotation_blocks;
  int64_t decalibrated_at_ns = -1;
  Eigen::Quaterniond last_q = Eigen::Quaterniond::Identity();

  // Moves window entries into `outside`, with the weight they have in long_stats now (their
  // weight when added, forgotten since): the oldest one, or every one of a segment.
  void EvictOldest() {
    MoveOutside(window.front());
    window.pop_front();
  }
  void EvictSegment(int segment) {
    for (auto it = window.begin(); it != window.end();) {
      if (it->data.segment != segment) {
        ++it;
        continue;
      }
      MoveOutside(*it);
      it = window.erase(it);
    }
  }
  void MoveOutside(const WindowEntry& e) {
    outside.Add(e.data, e.data.segment, e.weight * std::exp(log_decay - e.log_decay));
  }
};

bool RigEstimatorOptions::Check(std::string* error) const {
  std::ostringstream e;
  if (!(keyframe_min_angle_deg >= 0.0))
    e << "keyframe_min_angle_deg must be >= 0";
  else if (!(keyframe_min_translation >= 0.0))
    e << "keyframe_min_translation must be >= 0";
  else if (keyframe_max_interval_ns <= 0)
    e << "keyframe_max_interval_ns must be > 0";
  else if (keyframe_history < 2)
    e << "keyframe_history must be >= 2, got " << keyframe_history;
  else if (!(pair_target_angle_deg > 0.0))
    e << "pair_target_angle_deg must be > 0";
  else if (!(pair_target_translation_fraction > 0.0))
    e << "pair_target_translation_fraction must be > 0";
  else if (pair_max_span_ns <= 0)
    e << "pair_max_span_ns must be > 0";
  else if (!(angle_gate_floor_deg > 0.0))
    e << "angle_gate_floor_deg must be > 0";
  else if (!(gate_sigmas > 0.0))
    e << "gate_sigmas must be > 0";
  else if (!(huber_sigmas > 0.0))
    e << "huber_sigmas must be > 0";
  else if (!(scale_gate > 0.0))
    e << "scale_gate must be > 0";
  else if (half_life_s < 0.0)
    e << "half_life_s must be >= 0 (0 = never forget)";
  else if (!(short_half_life_s > 0.0))
    e << "short_half_life_s must be > 0";
  else if (max_open_segments < 1)
    e << "max_open_segments must be >= 1";
  else if (!(alpha_maxrot_deg >= 0.0 && alpha_maxrot_deg < 180.0))
    e << "alpha_maxrot_deg must be in [0, 180)";
  else if (!(alpha_maxrot_noise_deg >= 0.0) || std::isinf(alpha_maxrot_noise_deg))
    e << "alpha_maxrot_noise_deg must be finite and >= 0 (0 = fixed alpha_maxrot_deg)";
  else if (window_size < 2)
    e << "window_size must be >= 2";
  else if (converged_min_motions < 2)
    e << "converged_min_motions must be >= 2";
  else if (!(min_tilt_snr >= 0.0))
    e << "min_tilt_snr must be >= 0";
  else if (!(max_axis_std_ratio > 0.0))
    e << "max_axis_std_ratio must be > 0";
  else if (!(planar_hysteresis >= 1.0))
    e << "planar_hysteresis must be >= 1 (1 = none)";
  else if (!(general_axis_spread_deg > 0.0))
    e << "general_axis_spread_deg must be > 0";
  else if (!(planar_axis_spread_deg >= 0.0))
    e << "planar_axis_spread_deg must be >= 0";
  else if (!(nominal_sigma >= 0.0) || std::isinf(nominal_sigma))
    e << "nominal_sigma must be finite and >= 0 (0 = no weighted prior)";
  else if (!(sigma_block_s >= 0.0) || std::isinf(sigma_block_s))
    e << "sigma_block_s must be finite and >= 0 (0 = off), got " << sigma_block_s;
  else if (sigma_blocks < 4 || sigma_blocks > 1000)
    e << "sigma_blocks must be in [4, 1000], got " << sigma_blocks;
  else if (sigma_min_blocks < 2 || sigma_min_blocks > sigma_blocks)
    e << "sigma_min_blocks must be in [2, sigma_blocks], got " << sigma_min_blocks;
  if (error) *error = e.str();
  return e.str().empty();
}

RigEstimator::RigEstimator(std::vector<std::string> camera_names, RigEstimatorOptions options)
    : names_(std::move(camera_names)), options_(std::move(options)) {
  estimate_.rig.master = names_.empty() ? "" : names_[0];
  for (size_t i = 1; i < names_.size(); ++i) {
    slaves_.push_back(std::make_unique<Slave>());
    slaves_.back()->rotation_blocks = MakeRotationBlocks(options_);
    SlaveCalibration c;
    c.name = names_[i];
    c.message = "initialising: no motion yet";
    estimate_.rig.slaves.push_back(c);
    estimate_.online.emplace_back();
  }
}

RigEstimator::~RigEstimator() = default;

const RigEstimate& RigEstimator::Estimate() const { return estimate_; }

void RigEstimator::AddSet(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses) {
  if ((estimate_.sets > 0 && t_ns <= estimate_.t_ns) || poses.empty() || !poses[0] ||
      !poses[0]->pose.q.coeffs().allFinite() || !poses[0]->pose.C.allFinite()) {
    ++estimate_.rejected_sets;
    return;
  }
  estimate_.t_ns = t_ns;
  ++estimate_.sets;
  const CameraPose& master = *poses[0];
  if (have_master_segment_ && master.segment != master_segment_) {
    // New master unit: positions and scales restart; rotations are unit-free and stay.
    ModuleLogger("calib")->info(
        "master odometry re-initialised (segment {} -> {}): position "
        "and scales restart in the new master unit",
        master_segment_, master.segment);
    for (auto& s : slaves_) {
      s->long_stats.ResetPosition();
      s->short_stats.ResetPosition();
      s->keyframes.clear();
      s->window.clear();
      s->outside = s->long_stats;
      s->refined.reset();
    }
    ++generation_;
  }
  master_segment_ = master.segment;
  have_master_segment_ = true;
  for (size_t i = 0; i < slaves_.size() && i + 1 < poses.size(); ++i) {
    if (!poses[i + 1]) continue;
    const CameraPose& slave = *poses[i + 1];
    if (!slave.pose.q.coeffs().allFinite() || !slave.pose.C.allFinite()) {
      ++slaves_[i]->counts.residual_outlier;
      PublishCounts(static_cast<int>(i));
      continue;
    }
    UpdateSlave(static_cast<int>(i), t_ns, master, slave);
  }
}

void RigEstimator::UpdateSlave(int index, int64_t t_ns, const CameraPose& master,
                               const CameraPose& slave) {
  Slave& s = *slaves_[index];
  const RigEstimatorOptions& o = options_;
  if (!s.keyframes.empty() && s.keyframes.back().segment != slave.segment) {
    s.keyframes.clear();  // pairs never cross a scale segment
  }
  s.online.segment = slave.segment;
  if (!s.keyframes.empty()) {
    const Keyframe& last = s.keyframes.back();
    const double angle = AngleBetween(last.master.q, master.pose.q) * kDegPerRad;
    const double trans = (master.pose.C - last.master.C).norm();
    if (angle < o.keyframe_min_angle_deg && trans < o.keyframe_min_translation &&
        t_ns - last.t_ns < o.keyframe_max_interval_ns) {
      return;
    }
  }
  s.keyframes.push_back({t_ns, master.pose, slave.pose, slave.segment});
  if (static_cast<int>(s.keyframes.size()) > o.keyframe_history) s.keyframes.pop_front();
  ++s.online.keyframes;
  if (s.keyframes.size() < 2) return;

  // Pair the new keyframe b with the latest a that gives a large enough motion.
  const Keyframe& b = s.keyframes.back();
  Eigen::Vector3d lo = b.master.C, hi = b.master.C;
  for (const auto& k : s.keyframes) {
    lo = lo.cwiseMin(k.master.C);
    hi = hi.cwiseMax(k.master.C);
  }
  const double target_trans = o.pair_target_translation_fraction * (hi - lo).norm();
  const double target_angle = o.pair_target_angle_deg * kRadPerDeg;
  int chosen = -1;
  for (int j = static_cast<int>(s.keyframes.size()) - 2; j >= 0; --j) {
    const Keyframe& a = s.keyframes[j];
    if (b.t_ns - a.t_ns > o.pair_max_span_ns) break;
    chosen = j;
    if (AngleBetween(a.master.q, b.master.q) >= target_angle ||
        (b.master.C - a.master.C).norm() >= target_trans) {
      break;
    }
  }
  if (chosen < 0) return;
  const Keyframe& a = s.keyframes[chosen];
  RigMotion m;
  m.master = a.master.Between(b.master);
  m.slave = a.slave.Between(b.slave);
  m.segment = b.segment;
  m.t_a_ns = a.t_ns;
  m.t_b_ns = b.t_ns;

  std::vector<MotionData> data = internal::ToMotionData({m});
  MotionData& md = data[0];
  ++s.counts.total;
  auto reject = [&](int* counter) {
    ++*counter;
    PublishCounts(index);
  };
  // The motion model follows every formed motion (not only accepted ones): once the rig has
  // rotated by the equal-error boundary at the measured rotation noise (thesis 5.2) the
  // general model applies, and the residual statistics restart.
  if (!s.general &&
      md.angle0 * kDegPerRad >= TranslationalBelowDeg(o, s.angle_var.value, s.angle_var.count)) {
    s.general = true;
    s.accepted_in_model = 0;
    s.rot_var = {};
    s.pos_var = {};
    s.model_changed_ns = m.t_b_ns;
  }
  const bool general = s.general;
  if (general && md.angle0 * kDegPerRad < o.pair_min_angle_deg) {
    reject(&s.counts.small_rotation);
    return;
  }
  const bool have_estimate =
      s.linear.usable() && (s.linear.motion_model != MotionModel::kTranslational) == general;
  if (s.linear.usable()) internal::AlignSignsWith(ToWxyz(s.linear.estimate.q), &data);

  // Gates. A residual gate that rejects gate_after_motions motions in a row has an estimate
  // that the motions contradict (formed early, from motions about one axis, say): it is the
  // estimate that is off, not the majority of the motions. Gating then restarts as after a
  // model change, so the next motions are accepted and the estimate can follow them.
  auto restart_locked_gates = [&] {
    if (++s.gate_rejections_in_row < o.gate_after_motions) return;
    ModuleLogger("calib")->info(
        "slave '{}': {} motions in a row contradict the estimate; residual gating restarts",
        names_[index + 1], s.gate_rejections_in_row);
    s.gate_rejections_in_row = 0;
    s.accepted_in_model = 0;
    s.rot_var = {};
    s.pos_var = {};
  };
  const bool gating = s.accepted_in_model >= o.gate_after_motions && have_estimate;
  const double angle_diff = std::abs(md.angle0 - md.anglei) * kDegPerRad;
  const double angle_gate =
      gating ? std::max(o.angle_gate_floor_deg, o.gate_sigmas * std::sqrt(s.angle_var.value))
             : 4.0 * o.angle_gate_floor_deg;
  if (angle_diff > angle_gate) {
    reject(&s.counts.angle_mismatch);
    return;
  }
  double weight = 1.0;
  double r_rot = 0.0, r_pos = -1.0;
  if (have_estimate) {
    const Similarity& e = s.linear.estimate;
    r_rot = internal::RotationResidual(md, ToWxyz(e.q));
    double scale = 0.0;
    for (const auto& sc : s.linear.scales) {
      if (sc.segment == md.segment) scale = sc.scale;
    }
    if (scale > 0.0) {
      r_pos = general ? internal::PositionResidual(md, e.q, e.C, scale)
                      : internal::TranslationalResidual(md, e.q, scale);
      // Screw-pitch invariant (4.18): the measured scale agrees with the current one.
      const double vi = md.qi.tail<3>().norm(), v0 = md.q0.tail<3>().norm();
      const double delta = 30.0 * 1e-3 * std::sqrt(s.ci_sq.value);  // 10x the 3-eps threshold
      if (gating && general && vi > 1e-9 && v0 > 1e-9) {
        const double si = md.Ci.dot(md.qi.tail<3>() / vi);
        if (std::abs(si) > delta) {
          const double measured = md.C0.dot(md.q0.tail<3>() / v0) / si;
          if (std::abs(measured / scale - 1.0) > o.scale_gate) {
            ++s.online.gated_scale;
            reject(&s.counts.residual_outlier);
            restart_locked_gates();
            return;
          }
        }
      }
    }
    if (gating) {
      double worst = general ? r_rot / std::sqrt(std::max(s.rot_var.value, 1e-300)) : 0.0;
      if (r_pos >= 0.0)
        worst = std::max(worst, r_pos / std::sqrt(std::max(s.pos_var.value, 1e-300)));
      if (worst > o.gate_sigmas) {
        reject(&s.counts.residual_outlier);
        restart_locked_gates();
        return;
      }
      if (worst > o.huber_sigmas) weight = o.huber_sigmas / worst;  // Huber
    }
  }
  s.gate_rejections_in_row = 0;
  s.angle_var.Add(angle_diff * angle_diff);
  {
    // The consecutive-keyframe motion ending at b: its angle invariant holds the drift of one
    // keyframe interval only.
    const Keyframe& p = s.keyframes[s.keyframes.size() - 2];
    const double consecutive =
        std::abs(AngleBetween(p.master.q, b.master.q) - AngleBetween(p.slave.q, b.slave.q)) *
        kDegPerRad;
    s.consecutive_angle_var.Add(consecutive * consecutive);
    s.pair_span.Add(static_cast<double>(s.keyframes.size() - 1 - chosen));
  }
  s.ci_sq.Add(md.Ci.squaredNorm());
  if (have_estimate) {
    s.rot_var.Add(r_rot * r_rot);
    if (r_pos >= 0.0) s.pos_var.Add(r_pos * r_pos);
  }
  ++s.accepted_in_model;

  // Forgetting, then accumulate.
  if (s.last_decay_ns >= 0) {
    const int64_t dt = m.t_b_ns - s.last_decay_ns;
    const double f = Forget(dt, o.half_life_s);
    s.long_stats.Decay(f);
    s.rotation_blocks.Decay(f);
    s.outside.Decay(f);
    s.log_decay += std::log(f);
    s.short_stats.Decay(Forget(dt, o.short_half_life_s));
  }
  s.last_decay_ns = m.t_b_ns;
  s.long_stats.Add(md, md.segment, weight);
  if (o.sigma_block_s > 0.0) {
    const Eigen::Matrix4d a = internal::RotationConstraintMatrix(md);
    s.rotation_blocks.Add(m.t_b_ns, weight * a.transpose() * a, weight);  // (4.10) per block
  }
  s.short_stats.Add(md, md.segment, weight);
  for (MotionStatistics* stats : {&s.long_stats, &s.short_stats}) {
    while (static_cast<int>(stats->segments().size()) > o.max_open_segments) {
      int oldest = stats->segments().begin()->first;
      if (oldest == md.segment) oldest = std::next(stats->segments().begin())->first;
      const Eigen::Quaterniond at =
          have_estimate ? s.linear.estimate.q : Eigen::Quaterniond::Identity();
      const internal::PlanarFrame frame = stats->SolvePlanarFrame();
      if (stats == &s.long_stats) {
        // The window keeps open segments only: the closed one's motions join the prior.
        s.EvictSegment(oldest);
        s.outside.MarginaliseSegment(oldest, at, frame);
      }
      stats->MarginaliseSegment(oldest, at, frame);
    }
  }
  s.window.push_back({m, weight, md, s.log_decay});
  if (static_cast<int>(s.window.size()) > o.window_size) s.EvictOldest();
  ++s.counts.used;
  s.online.last_update_ns = m.t_b_ns;
  Publish(index);
}

void RigEstimator::PublishCounts(int index) {
  const MotionCounts& c = slaves_[index]->counts;
  MotionCounts& p = estimate_.rig.slaves[index].motions;
  p.total = c.total;
  p.small_rotation = c.small_rotation;
  p.angle_mismatch = c.angle_mismatch;
  p.residual_outlier = c.residual_outlier;
}

void RigEstimator::Publish(int index) {
  Slave& s = *slaves_[index];
  const RigEstimatorOptions& o = options_;
  const std::optional<Similarity> nominal =
      index < static_cast<int>(o.nominal.size()) ? o.nominal[index] : std::nullopt;
  MotionModelChoice choice;
  choice.rotating = s.general;
  choice.noise_deg = std::sqrt(s.angle_var.value);
  choice.boundary_deg = TranslationalBelowDeg(o, s.angle_var.value, s.angle_var.count);
  const bool was_general_model = s.general_model;
  s.linear = SolveStatistics(s.long_stats, o, nominal, s.online.segment, choice, &s.general_model);
  if (s.general && s.general_model != was_general_model) {
    s.model_changed_ns = s.online.last_update_ns;  // general <-> planar
  }
  for (const auto& [id, stats] : s.long_stats.segments()) {
    for (const auto& sc : s.linear.scales) {
      if (sc.segment == id) s.long_stats.SetSegmentScale(id, sc.scale);
    }
  }
  SlaveOnlineState& online = s.online;
  online.flags = 0;

  // Decalibration: the short window disagrees with the long one for several keyframes.
  online.short_long_rot_deg = 0.0;
  // Planar motion: the short window determines the rotation about the axis from a few
  // translations only; it is not compared (no decalibration detection on planar drives).
  bool short_general = s.general_model;
  const SlaveCalibration short_est =
      s.linear.observability.planar
          ? SlaveCalibration{}
          : SolveStatistics(s.short_stats, o, nominal, online.segment, choice, &short_general);
  // Only a settled long-window estimate can be contradicted: enough motions and a rotation
  // with a small σ (the first keyframes of a planar drive can look general with the rotation
  // about the axis undetermined in both windows; the translational model has no σ, and a
  // car driving straight does not determine the rotation about its direction of travel).
  // The σ of both windows count the shared drift of overlapping pairs (OverlapFactor). Across
  // a change of the motion model (translational -> rotating, general <-> planar) the short
  // window still holds the other model's motions: no comparison until it has forgotten them.
  const double overlap =
      std::sqrt(OverlapFactor(s.angle_var, s.consecutive_angle_var, s.pair_span));
  // The published rotation σ: at least the cluster-robust one of the time blocks (rotating
  // rig). Not for the decalibration test: after a bump the blocks disagree, which inflates
  // that σ exactly when the windows should be found to differ.
  const double rot_factor =
      o.sigma_block_s > 0.0 && s.general
          ? std::max(overlap, std::sqrt(s.rotation_blocks.VarianceFactor(o.sigma_min_blocks)))
          : overlap;
  const double long_sigma = overlap * s.linear.rot_std_deg;
  const bool settled = s.linear.motions.used >= o.converged_min_motions && long_sigma > 0.0 &&
                       long_sigma <= o.converged_rot_std_deg;
  const bool model_settled =
      s.model_changed_ns < 0 ||
      online.last_update_ns - s.model_changed_ns >= static_cast<int64_t>(o.short_half_life_s * 1e9);
  if (settled && model_settled && s.linear.usable() && short_est.usable() &&
      !s.linear.observability.planar && !short_est.observability.planar &&
      short_est.motions.used >= o.converged_min_motions / 2) {
    const double diff = AngleBetween(s.linear.estimate.q, short_est.estimate.q) * kDegPerRad;
    online.short_long_rot_deg = diff;
    const double sigma = overlap * std::hypot(s.linear.rot_std_deg, short_est.rot_std_deg);
    bool disagree = diff > std::max(o.decalibration_min_deg, o.decalibration_sigmas * sigma);
    if (o.decalibration_min_translation > 0.0 && s.linear.position_observable) {
      disagree = disagree || (s.linear.estimate.C - short_est.estimate.C).norm() >
                                 o.decalibration_min_translation;
    }
    s.disagreements = disagree ? s.disagreements + 1 : 0;
    if (s.disagreements >= o.decalibration_confirmations) {
      ModuleLogger("calib")->warn(
          "slave '{}' decalibrated: short and long windows differ by {:.2f} deg; following the "
          "new calibration",
          names_[index + 1], diff);
      s.long_stats = s.short_stats;  // re-converge on the recent motions
      s.rotation_blocks.Clear();
      s.window.clear();
      s.outside = s.long_stats;
      s.refined.reset();
      s.disagreements = 0;
      s.stable = 0;
      s.decalibrated_at_ns = online.last_update_ns;
      ++online.decalibration_events;
      ++generation_;
      s.linear =
          SolveStatistics(s.long_stats, o, nominal, online.segment, choice, &s.general_model);
    }
  }
  const bool decalibrated =
      s.decalibrated_at_ns >= 0 && online.last_update_ns - s.decalibrated_at_ns <
                                       static_cast<int64_t>(o.short_half_life_s * 1e9);
  if (decalibrated) online.flags |= kFlagDecalibrated;

  SlaveCalibration published = s.linear;
  if (s.refined && s.linear.usable()) {
    const double sigma = std::max(rot_factor * s.linear.rot_std_deg, 1e-3);  // shared drift counted
    if (AngleBetween(s.refined->estimate.q, s.linear.estimate.q) * kDegPerRad <=
        o.gate_sigmas * sigma) {
      published = *s.refined;
      published.motions = s.linear.motions;
      online.flags |= kFlagRefined;
    }
  }
  published.name = names_[index + 1];
  published.motions.used = s.counts.used;
  // The covariance takes the motions as independent; overlapping pairs and drift make motions
  // close in time err alike, so the published σ count it (OverlapFactor; the time blocks for
  // the rotation), and convergence is judged on them.
  published.rot_std_deg *= rot_factor;
  if (overlap > 1.0) {
    published.pos_std *= overlap;
    if (std::isfinite(published.axis_offset_std)) published.axis_offset_std *= overlap;
    for (SegmentScale& sc : published.scales) sc.std *= overlap;
  }

  if (!published.usable()) {
    online.flags |= kFlagInitialising;
  } else {
    // Stability of the linear estimate (a refinement being published is no change).
    const double change = AngleBetween(s.linear.estimate.q, s.last_q) * kDegPerRad;
    s.stable = change <= std::max(rot_factor * s.linear.rot_std_deg, 0.01) ? s.stable + 1 : 0;
    s.last_q = s.linear.estimate.q;
    if (published.motion_model == MotionModel::kTranslational)
      online.flags |= kFlagTranslationalOnly;
    if (published.observability.planar) online.flags |= kFlagPlanar;
    const double c_ref = std::max(1.0, published.estimate.C.norm());
    const bool position_ok = !published.position_observable || published.observability.planar ||
                             published.pos_std.maxCoeff() <= o.converged_pos_std_fraction * c_ref;
    if (published.motions.used >= o.converged_min_motions &&
        published.rot_std_deg <= o.converged_rot_std_deg && position_ok &&
        s.stable >= o.converged_stable_keyframes && !decalibrated) {
      online.flags |= kFlagConverged;
    }
  }
  std::ostringstream msg;
  msg << (online.flags & kFlagConverged ? "converged" : "converging") << ": "
      << published.motions.used << " motions used, " << published.motions.rejected()
      << " rejected; " << ToString(published.motion_model) << " motion";
  if (online.flags & kFlagTranslationalOnly) {
    // Thesis 5.2: why the translational model.
    msg << fmt::format(
        " (rotation and scale only: largest rotation {:.2f} deg < {:.2f} deg, the equal-error "
        "boundary at the rotation noise {:.3f} deg)",
        published.observability.max_rotation_deg, published.observability.translational_below_deg,
        published.observability.rotation_noise_deg);
    if (!std::isfinite(published.rot_std_deg)) {
      msg << "; the translations are all parallel: the rotation about their direction is "
             "undetermined";
    }
  }
  if (online.flags & kFlagPlanar) {
    const Eigen::Vector3d& a = published.observability.planar_axis;
    msg << fmt::format(
        " ({}): C along the rotation axis [{:.3f}, {:.3f}, {:.3f}] is unobservable, {}",
        s.linear.message, a.x(), a.y(), a.z(),
        published.unobservable_from_prior ? "taken from the nominal mounting"
                                          : "reported as 0 (unknown)");
  } else if (published.motion_model == MotionModel::kGeneral &&
             published.observability.axis_std_ratio > 3.0 &&
             std::isfinite(published.axis_offset_std)) {
    msg << fmt::format(" (nearly planar: sigma of C along the mean rotation axis {:.4f})",
                       published.axis_offset_std);
  }
  if (decalibrated) msg << "; DECALIBRATED (camera moved), re-converging";
  if (!published.usable()) msg.str(published.message);
  published.message = msg.str();
  estimate_.rig.slaves[index] = published;
  estimate_.online[index] = online;
  PublishCounts(index);
}

RefinementJob RigEstimator::MakeRefinementJob(int slave) const {
  RefinementJob job;
  job.slave = slave;
  job.generation = generation_;
  const Slave& s = *slaves_.at(slave);
  for (const auto& w : s.window) {
    job.motions.push_back(w.motion);
    job.weights.push_back(std::exp(s.log_decay - w.log_decay));
  }
  job.start = s.linear;
  job.prior = s.outside.Quadratic();
  const std::optional<Similarity>& nominal =
      slave < static_cast<int>(options_.nominal.size()) ? options_.nominal[slave] : std::nullopt;
  if (nominal && options_.nominal_sigma > 0.0) {
    job.axis_prior = s.linear.observability.planar_axis.dot(nominal->C);
    job.axis_prior_sigma = options_.nominal_sigma;
  }
  return job;
}

bool RigEstimator::ApplyRefinement(const RefinementJob& job, const SlaveCalibration& refined) {
  if (job.generation != generation_ || !refined.usable()) return false;
  Slave& s = *slaves_.at(job.slave);
  s.refined = refined;
  Publish(job.slave);
  return (estimate_.online[job.slave].flags & kFlagRefined) != 0;
}

SlaveCalibration RefineWindow(const RefinementJob& job) {
  SlaveCalibration out = job.start;
  if (!job.start.usable() || static_cast<int>(job.motions.size()) + job.prior.motions < 3) {
    return out;
  }
  std::vector<MotionData> data = internal::ToMotionData(job.motions);
  internal::AlignSignsWith(ToWxyz(job.start.estimate.q), &data);
  std::map<int, int> index;
  internal::RefinementInput input;
  input.q = job.start.estimate.q;
  input.C = job.start.estimate.C;
  input.translational = job.start.motion_model == MotionModel::kTranslational;
  const bool planar = job.start.motion_model == MotionModel::kPlanar;
  const Eigen::Vector3d axis = job.start.observability.planar_axis;
  if (!input.translational && axis.norm() > 0.5 && (planar || job.axis_prior_sigma > 0.0)) {
    // The reduced parameter set: C = B p + h a, h fixed in the planar model, pulled towards
    // the nominal by a weighted term in the general model.
    input.axis = axis;
    input.axis_prior = job.axis_prior;
    input.axis_prior_sigma = job.axis_prior_sigma;
    input.axis_offset_fixed = planar;
  }
  auto scale_index = [&](int segment) {
    auto [it, inserted] = index.emplace(segment, static_cast<int>(index.size()));
    if (inserted) {
      double scale = job.start.estimate.scale;
      for (const auto& sc : job.start.scales) {
        if (sc.segment == segment) scale = sc.scale;
      }
      input.scales.push_back(scale);
    }
    return it->second;
  };
  for (auto& m : data) m.scale_index = scale_index(m.segment);
  if (job.weights.size() == data.size()) input.weights = job.weights;
  std::vector<double> prior_scales;
  if (job.prior.weight > 0.0) {
    input.prior = &job.prior;
    for (int segment : job.prior.segments) {
      input.prior_scale_index.push_back(scale_index(segment));
      prior_scales.push_back(input.scales[input.prior_scale_index.back()]);
    }
  }
  // Noise levels from the residuals at the start, of the window's motions and the prior's.
  double ss_rot = 0.0, ss_pos = 0.0, k = 0.0;
  for (size_t j = 0; j < data.size(); ++j) {
    const internal::MotionData& m = data[j];
    const double w = input.weights.empty() ? 1.0 : input.weights[j];
    const double s = input.scales[m.scale_index];
    ss_rot += w * std::pow(internal::RotationResidual(m, ToWxyz(input.q)), 2);
    ss_pos += w * std::pow(input.translational ? internal::TranslationalResidual(m, input.q, s)
                                               : internal::PositionResidual(m, input.q, input.C, s),
                           2);
    k += w;
  }
  if (input.prior != nullptr) {
    ss_rot += internal::RotationPriorValue(job.prior, input.q);
    ss_pos += internal::PositionPriorValue(
        job.prior, input.q, input.translational ? Eigen::Vector3d::Zero() : input.C, prior_scales);
    k += job.prior.weight;
  }
  input.sigma_rotation = std::max(std::sqrt(ss_rot / std::max(1.0, 4 * k - 3)), 1e-12);
  input.sigma_position =
      std::max(std::sqrt(ss_pos / std::max(1.0, 3 * k - (planar ? 6 : 7))), 1e-12);
  CalibrationOptions options;
  options.robust_loss = job.robust_loss ? RobustLoss::kHuber : RobustLoss::kNone;
  const internal::RefinementResult r = internal::RefineNonlinear(data, input, options);
  if (!r.q.coeffs().allFinite() || !r.C.allFinite()) return out;
  out.estimate.q = r.q;
  if (!input.translational) out.estimate.C = r.C;
  for (auto& sc : out.scales) {
    auto it = index.find(sc.segment);
    if (it != index.end()) {
      sc.scale = r.scales[it->second];
      sc.std = r.scale_std[it->second];
    }
  }
  const int newest = !job.motions.empty()          ? job.motions.back().segment
                     : !job.prior.segments.empty() ? job.prior.segments.back()
                                                   : -1;
  const auto current = index.find(newest);
  if (current != index.end()) out.estimate.scale = r.scales[current->second];
  if (r.covariance_ok) {
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(r.cov_rotation);
    out.rot_std_deg = std::sqrt(std::max(0.0, eig.eigenvalues()(2))) * kDegPerRad;
    if (!input.translational) out.pos_std = r.cov_position.diagonal().cwiseMax(0.0).cwiseSqrt();
    if (!input.translational && !input.axis_offset_fixed && input.axis.norm() > 0.5) {
      out.axis_offset_std = r.axis_std;
    } else if (!input.translational && !planar && axis.norm() > 0.5) {
      out.axis_offset_std = std::sqrt(std::max(0.0, axis.dot(r.cov_position * axis)));
    } else if (planar && job.axis_prior_sigma > 0.0) {
      const Eigen::Matrix3d cov =
          r.cov_position + job.axis_prior_sigma * job.axis_prior_sigma * axis * axis.transpose();
      out.pos_std = cov.diagonal().cwiseMax(0.0).cwiseSqrt();
    }
  }
  out.termination = r.converged ? Termination::kConverged : Termination::kNoConvergence;
  return out;
}

std::string RigEstimator::SerializeState() const {
  std::ostringstream body;
  body.precision(17);
  body << "cameras " << names_.size();
  for (const auto& n : names_) body << ' ' << n;
  body << "\nmaster_segment " << master_segment_ << ' ' << (have_master_segment_ ? 1 : 0) << '\n';
  for (size_t i = 0; i < slaves_.size(); ++i) {
    const Slave& s = *slaves_[i];
    body << "slave " << i << "\ncounts " << s.counts.total << ' ' << s.counts.used << ' '
         << s.counts.small_rotation << ' ' << s.counts.angle_mismatch << ' '
         << s.counts.residual_outlier << "\nnoise " << s.angle_var.value << ' ' << s.angle_var.count
         << ' ' << s.rot_var.value << ' ' << s.rot_var.count << ' ' << s.pos_var.value << ' '
         << s.pos_var.count << ' ' << s.ci_sq.value << ' ' << s.ci_sq.count << "\nsegment "
         << s.online.segment << "\nmodel " << (s.general ? 1 : 0) << ' '
         << (s.general_model ? 1 : 0) << "\nlong\n"
         << s.long_stats.Serialize() << "short\n"
         << s.short_stats.Serialize();
  }
  const std::string text = body.str();
  std::ostringstream out;
  out << "rigcal-estimator-state " << kStateVersion << '\n'
      << text << "checksum " << std::hex << Fnv1a(text) << '\n';
  return out.str();
}

bool RigEstimator::RestoreState(const std::string& text, std::string* error) {
  auto fail = [error](const std::string& why) {
    if (error) *error = why;
    return false;
  };
  std::istringstream in(text);
  std::string magic;
  int version = 0;
  if (!(in >> magic >> version) || magic != "rigcal-estimator-state") {
    return fail("not a rigcal estimator state (bad header)");
  }
  if (version < kOldestStateVersion || version > kStateVersion) {
    return fail("state version " + std::to_string(version) + ", this build reads versions " +
                std::to_string(kOldestStateVersion) + " to " + std::to_string(kStateVersion));
  }
  const size_t body_start = text.find('\n') + 1;
  const size_t sum_pos = text.rfind("checksum ");
  if (sum_pos == std::string::npos || sum_pos < body_start) return fail("missing checksum");
  const std::string body = text.substr(body_start, sum_pos - body_start);
  std::istringstream sum_in(text.substr(sum_pos + 9));
  uint64_t stored = 0;
  if (!(sum_in >> std::hex >> stored) || stored != Fnv1a(body)) {
    return fail("checksum mismatch (file corrupt or truncated)");
  }
  std::istringstream b(body);
  std::string word;
  size_t count = 0;
  if (!(b >> word >> count) || word != "cameras" || count != names_.size()) {
    return fail("state is for a different rig (camera count)");
  }
  for (const auto& n : names_) {
    if (!(b >> word) || word != n) return fail("state is for a different rig (camera '" + n + "')");
  }
  int master_segment = 0, have = 0;
  if (!(b >> word >> master_segment >> have) || word != "master_segment") {
    return fail("malformed master_segment");
  }
  std::vector<std::unique_ptr<Slave>> restored;
  std::string rest((std::istreambuf_iterator<char>(b)), std::istreambuf_iterator<char>());
  for (size_t i = 0; i < slaves_.size(); ++i) {
    auto s = std::make_unique<Slave>();
    s->rotation_blocks = MakeRotationBlocks(options_);  // not saved: rebuilt from new motions
    std::istringstream sin(rest);
    size_t idx = 0;
    if (!(sin >> word >> idx) || word != "slave" || idx != i) return fail("malformed slave block");
    if (!(sin >> word >> s->counts.total >> s->counts.used >> s->counts.small_rotation >>
          s->counts.angle_mismatch >> s->counts.residual_outlier) ||
        word != "counts") {
      return fail("malformed counts of slave " + names_[i + 1]);
    }
    if (!(sin >> word >> s->angle_var.value >> s->angle_var.count >> s->rot_var.value >>
          s->rot_var.count >> s->pos_var.value >> s->pos_var.count >> s->ci_sq.value >>
          s->ci_sq.count) ||
        word != "noise") {
      return fail("malformed noise of slave " + names_[i + 1]);
    }
    if (!(sin >> word >> s->online.segment) || word != "segment") return fail("malformed segment");
    int rotating = 0, general_model = 0;
    if (!(sin >> word >> rotating >> general_model) || word != "model") {
      return fail("malformed model of slave " + names_[i + 1]);
    }
    s->general = rotating != 0;
    s->general_model = general_model != 0;
    std::string remaining((std::istreambuf_iterator<char>(sin)), std::istreambuf_iterator<char>());
    const size_t long_pos = remaining.find("long\n");
    const size_t short_pos = remaining.find("short\n");
    if (long_pos == std::string::npos || short_pos == std::string::npos) {
      return fail("malformed statistics of slave " + names_[i + 1]);
    }
    const size_t next = remaining.find("\nslave ", short_pos);
    const std::string long_text = remaining.substr(long_pos + 5, short_pos - long_pos - 5);
    const std::string short_text = remaining.substr(
        short_pos + 6, next == std::string::npos ? std::string::npos : next + 1 - short_pos - 6);
    if (!s->long_stats.Parse(long_text) || !s->short_stats.Parse(short_text)) {
      return fail("malformed statistics of slave " + names_[i + 1]);
    }
    s->outside = s->long_stats;  // the window is not saved: all of it is prior now
    rest = next == std::string::npos ? "" : remaining.substr(next + 1);
    restored.push_back(std::move(s));
  }
  slaves_ = std::move(restored);
  master_segment_ = master_segment;
  have_master_segment_ = have != 0;
  ++generation_;
  for (size_t i = 0; i < slaves_.size(); ++i) {
    slaves_[i]->online.segment = slaves_[i]->online.segment;
    Publish(static_cast<int>(i));
  }
  return true;
}

}  // namespace rigcal
