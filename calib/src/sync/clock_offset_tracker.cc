// SPDX-License-Identifier: Apache-2.0
// ClockOffsetTracker: per slave, the angular-speed correlation to start, then a Kalman filter on
// [offset, drift] fed by rotation-angle measurements, and jump detection.
#include "rigcal/calib/clock_offset_tracker.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "rigcal/base/logging.h"
#include "rigcal/calib/clock_offset.h"
#include "rigcal/calib/pose_interpolation.h"

namespace rigcal {
namespace {

constexpr double kPpm = 1e-6;
constexpr int64_t kNsPerS = 1'000'000'000;
// Slave::t_ns of a state that starts at its first measurement window (a given offset that the
// master's clock restart made estimated).
constexpr int64_t kStateTimeUnset = std::numeric_limits<int64_t>::min();

int64_t Ns(double s) { return std::llround(s * 1e9); }
double S(int64_t ns) { return static_cast<double>(ns) * 1e-9; }

// The poses of `poses` with stamps in [from_ns, to_ns] (own clock) as a trajectory.
TimedTrajectory Window(const std::deque<CameraPose>& poses, const std::string& name,
                       int64_t from_ns, int64_t to_ns) {
  TimedTrajectory out;
  out.name = name;
  for (const CameraPose& p : poses) {
    if (p.t_ns < from_ns || p.t_ns > to_ns) continue;
    out.t_ns.push_back(p.t_ns);
    out.poses.push_back(p.pose);
    out.segment.push_back(p.segment);
  }
  return out;
}

}  // namespace

Status ClockOffsetOptions::Check(int num_slaves) const {
  std::ostringstream e;
  if (!given_s.empty() && static_cast<int>(given_s.size()) != num_slaves)
    e << "given_s: must be empty or have one entry per slave (" << num_slaves << "), got "
      << given_s.size();
  else if (!(init_window_s > 2.0))
    e << "init_window_s: must be > 2 s, got " << init_window_s;
  else if (!(search_window_s > 0.0))
    e << "search_window_s: must be > 0, got " << search_window_s;
  else if (!(measure_window_s > 0.0))
    e << "measure_window_s: must be > 0, got " << measure_window_s;
  else if (!(motion_span_s > 0.0))
    e << "motion_span_s: must be > 0, got " << motion_span_s;
  else if (!(drift_ppm >= 0.0) || !std::isfinite(drift_ppm))
    e << "drift_ppm: must be >= 0, got " << drift_ppm;
  else if (!(drift_walk_ppm_per_sqrt_s >= 0.0) || !std::isfinite(drift_walk_ppm_per_sqrt_s))
    e << "drift_walk_ppm_per_sqrt_s: must be >= 0, got " << drift_walk_ppm_per_sqrt_s;
  else if (!(offset_walk_s_per_sqrt_s >= 0.0) || !std::isfinite(offset_walk_s_per_sqrt_s))
    e << "offset_walk_s_per_sqrt_s: must be >= 0, got " << offset_walk_s_per_sqrt_s;
  else if (!(jump_sigmas > 0.0))
    e << "jump_sigmas: must be > 0, got " << jump_sigmas;
  else if (!(jump_min_s >= 0.0))
    e << "jump_min_s: must be >= 0, got " << jump_min_s;
  else if (jump_confirmations < 1)
    e << "jump_confirmations: must be >= 1, got " << jump_confirmations;
  else if (!(history_s >= init_window_s + 2.0 * measure_window_s) || !std::isfinite(history_s))
    e << "history_s: must be >= init_window_s + 2 * measure_window_s, got " << history_s;
  if (e.str().empty()) return Status::Ok();
  return Error{"time_offset." + e.str()};
}

struct ClockOffsetTracker::Slave {
  bool estimated = true;
  bool initialised = false;
  Eigen::Vector2d x = Eigen::Vector2d::Zero();  // [τ (s), ρ (s/s)] at time t_ns
  Eigen::Matrix2d P = Eigen::Matrix2d::Zero();
  int64_t t_ns = 0;          // master time of x
  int64_t since_ns = 0;      // master time from which poses serve the (re)initialisation
  int64_t next_from_ns = 0;  // start of the next measurement window (master clock)
  int outliers = 0;
  int64_t first_outlier_ns = 0;
  int measurements = 0;
  int jumps = 0;
  int64_t usable_from_ns = 0;
  bool ever_initialised = false;
  // The (re)initialisation searches within ± search_s around prior_s.
  double prior_s = 0.0;
  double search_s = 0.0;
  // The slave's newest stamp when its poses were first seen to end before the predicted
  // instants of a window the master had passed (-1: not lagging).
  int64_t lag_slave_ns = -1;
};

ClockOffsetTracker::ClockOffsetTracker(std::vector<std::string> camera_names,
                                       ClockOffsetOptions options)
    : names_(std::move(camera_names)), options_(std::move(options)) {
  poses_.resize(names_.size());
  const size_t n = names_.empty() ? 0 : names_.size() - 1;
  slaves_.resize(n);
  for (size_t i = 0; i < n; ++i) {
    slaves_[i].search_s = options_.search_window_s;
    if (i < options_.given_s.size() && options_.given_s[i]) {
      slaves_[i].estimated = false;
      slaves_[i].initialised = true;
      slaves_[i].x << *options_.given_s[i], 0.0;
    }
  }
}

ClockOffsetTracker::~ClockOffsetTracker() = default;

int ClockOffsetTracker::num_slaves() const { return static_cast<int>(slaves_.size()); }

void ClockOffsetTracker::Trim(std::deque<CameraPose>* poses) const {
  const int64_t keep_ns = Ns(options_.history_s);
  while (!poses->empty() && poses->back().t_ns - poses->front().t_ns > keep_ns) poses->pop_front();
}

bool ClockOffsetTracker::Add(const CameraPose& pose) {
  if (pose.camera < 0 || pose.camera >= static_cast<int>(poses_.size())) return false;
  std::deque<CameraPose>& poses = poses_[pose.camera];
  if (!poses.empty() && pose.t_ns <= poses.back().t_ns) return false;
  poses.push_back(pose);
  Trim(&poses);
  if (pose.camera != 0) return false;
  bool changed = false;
  for (int i = 0; i < num_slaves(); ++i) {
    if (!slaves_[i].estimated) continue;
    const SlaveClockOffset before = SlaveOffset(i);
    Update(i);
    const SlaveClockOffset after = SlaveOffset(i);
    changed = changed || before.known != after.known || before.offset_s != after.offset_s ||
              before.jumps != after.jumps;
  }
  return changed;
}

void ClockOffsetTracker::Update(int i) {
  Slave& s = slaves_[i];
  if (!s.initialised) {
    Initialise(i);
    if (!s.initialised) return;
  }
  while (Measure(i)) {
  }
}

bool ClockOffsetTracker::Initialise(int i) {
  Slave& s = slaves_[i];
  const std::deque<CameraPose>& master = poses_[0];
  const std::deque<CameraPose>& slave = poses_[i + 1];
  if (master.empty() || slave.empty()) return false;
  const int64_t from = std::max(s.since_ns, master.front().t_ns);
  const int64_t newest = master.back().t_ns;
  if (newest - from < Ns(options_.init_window_s)) return false;
  const int64_t margin = Ns(s.search_s);
  const TimedTrajectory m = Window(master, names_[0], from, newest);
  const TimedTrajectory sl = Window(slave, names_[i + 1], from + Ns(s.prior_s) - margin,
                                    std::numeric_limits<int64_t>::max());
  TimeOffsetOptions o;
  o.search_window_s = s.search_s;
  o.center_s = s.prior_s;
  o.min_overlap_s = std::min(2.0, 0.5 * options_.init_window_s);
  const auto correlated = CorrelateAngularSpeed(m, sl, o);
  if (!correlated) {
    // Not enough data or motion yet: try again on the newest window.
    s.since_ns = newest - Ns(options_.init_window_s) / 2;
    return false;
  }
  // The correlation's grid is half a frame interval: its error is within a quarter of one.
  const double h = 0.5 * S(std::min(MedianInterval(m.t_ns), MedianInterval(sl.t_ns)));
  s.initialised = true;
  s.ever_initialised = true;
  s.x << correlated->offset_s, 0.0;
  s.P.setZero();
  s.P(0, 0) = std::pow(0.5 * h, 2);
  s.P(1, 1) = std::pow(options_.drift_ppm * kPpm, 2);
  s.t_ns = m.t_ns.front();
  s.next_from_ns = m.t_ns.front();
  s.outliers = 0;
  s.measurements = 0;
  ModuleLogger("calib")->info(
      "time offset of '{}': initialised at {:.6f} s (angular-speed correlation {:.3f})",
      names_[i + 1], correlated->offset_s, correlated->correlation);
  return true;
}

bool ClockOffsetTracker::Measure(int i) {
  Slave& s = slaves_[i];
  const std::deque<CameraPose>& master = poses_[0];
  const std::deque<CameraPose>& slave = poses_[i + 1];
  if (master.empty() || slave.empty()) return false;
  const int64_t from = std::max(s.next_from_ns, master.front().t_ns);
  const int64_t to = from + Ns(options_.measure_window_s);
  if (s.t_ns == kStateTimeUnset) s.t_ns = from;
  // The motions end a span after the window; the slave must cover them at any offset searched.
  const int64_t frame = std::max<int64_t>(
      1, (slave.back().t_ns - slave.front().t_ns) / std::max<int64_t>(1, slave.size() - 1));
  const int64_t needed = to + Ns(options_.motion_span_s) + 2 * frame;
  // Predicted offset at the window's centre.
  const double dt = S(from + (to - from) / 2 - s.t_ns);
  Eigen::Matrix2d F;
  F << 1.0, dt, 0.0, 1.0;
  const Eigen::Vector2d x = F * s.x;
  const double adt = std::abs(dt);
  const double qr = std::pow(options_.drift_walk_ppm_per_sqrt_s * kPpm, 2);
  const double qt = std::pow(options_.offset_walk_s_per_sqrt_s, 2);
  Eigen::Matrix2d Q;
  Q << qr * adt * adt * adt / 3.0 + qt * adt, qr * adt * adt / 2.0, qr * adt * adt / 2.0, qr * adt;
  const Eigen::Matrix2d P = F * s.P * F.transpose() + Q;
  const double half_width = std::max(S(frame), 5.0 * std::sqrt(P(0, 0)));
  if (master.back().t_ns < needed) return false;
  if (slave.back().t_ns - Ns(x(0) + half_width) < needed) {
    // The slave's poses end before the predicted instants: wait for them, unless the master is
    // a whole window further and the slave delivered half a window of poses meanwhile (its
    // clock stepped back: an outlier window; a camera that stopped is only waited for).
    if (master.back().t_ns < needed + Ns(options_.measure_window_s)) return false;
    if (s.lag_slave_ns < 0) s.lag_slave_ns = slave.back().t_ns;
    if (slave.back().t_ns - s.lag_slave_ns < Ns(options_.measure_window_s) / 2) return false;
    s.lag_slave_ns = -1;
    s.next_from_ns = to;
    const double behind = S(needed - slave.back().t_ns) + x(0);
    return Outlier(i, from, -behind, x(0), std::sqrt(P(0, 0)));
  }
  s.lag_slave_ns = -1;
  s.next_from_ns = to;
  const TimedTrajectory m = Window(master, names_[0], from - frame, needed);
  const TimedTrajectory sl = Window(slave, names_[i + 1], from + Ns(x(0) - half_width) - 3 * frame,
                                    needed + Ns(x(0) + half_width) + 3 * frame);
  const auto z = MeasureOffsetFromAngles(m, sl, from, to, x(0), half_width, options_.motion_span_s);
  // The minimum at an end of the searched interval: the offset lies beyond it, however poorly
  // the window determines where.
  if (z && z->at_bound) return Outlier(i, from, z->offset_s, x(0), std::sqrt(P(0, 0)));
  // No information in this window (too few motions, too little angular acceleration).
  if (!z || !std::isfinite(z->std_s) || z->std_s > half_width / 3.0) return true;
  const double r = z->std_s * z->std_s;
  const double nu = z->offset_s - x(0);
  const double sigma = std::sqrt(P(0, 0) + r);
  if (std::abs(nu) > options_.jump_sigmas * sigma && std::abs(nu) > options_.jump_min_s) {
    return Outlier(i, from, z->offset_s, x(0), sigma);
  }
  s.outliers = 0;
  // Kalman update with H = [1 0].
  const Eigen::Vector2d k = P.col(0) / (P(0, 0) + r);
  s.x = x + k * nu;
  s.P = P - k * P.row(0);
  s.t_ns = from + (to - from) / 2;
  if (s.measurements++ == 0) s.usable_from_ns = master.back().t_ns;
  return true;
}

bool ClockOffsetTracker::Outlier(int i, int64_t from_ns, double measured_s, double predicted_s,
                                 double sigma_s) {
  Slave& s = slaves_[i];
  const auto log = ModuleLogger("calib");
  // The re-initialisation starts at the first window that disagrees: its poses before the jump
  // are few, and the jump's spike in the angular speed is capped (clock_offset.cc).
  if (s.outliers++ == 0) s.first_outlier_ns = from_ns;
  log->debug("time offset of '{}': measured {:.6f} s, predicted {:.6f} ± {:.2g} s ({} in a row)",
             names_[i + 1], measured_s, predicted_s, sigma_s, s.outliers);
  if (s.outliers < options_.jump_confirmations) return true;
  // A jump of an offset the measurements confirmed (not a failed (re)initialisation).
  if (s.measurements > 0) ++s.jumps;
  log->warn(
      "time offset of '{}' jumped: measured {:.6f} s where {:.6f} ± {:.2g} s was predicted ({} "
      "windows in a row; camera restarted?): re-estimating it from the poses since then",
      names_[i + 1], measured_s, predicted_s, sigma_s, s.outliers);
  s.initialised = false;
  s.since_ns = s.first_outlier_ns;
  s.outliers = 0;
  s.lag_slave_ns = -1;
  s.prior_s = predicted_s;
  s.search_s = options_.search_window_s;
  return false;
}

SlaveClockOffset ClockOffsetTracker::SlaveOffset(int i) const {
  const Slave& s = slaves_[i];
  SlaveClockOffset out;
  out.estimated = s.estimated;
  out.jumps = s.jumps;
  out.measurements = s.measurements;
  out.usable_from_ns = s.usable_from_ns;
  if (!s.estimated) {
    out.known = true;
    out.offset_s = s.x(0);
    return out;
  }
  if (!s.initialised) return out;
  // Predicted to the newest master stamp.
  // (No state time yet, a given offset re-estimated after a master restart: nothing to predict.)
  const int64_t now = poses_[0].empty() ? s.t_ns : std::max(s.t_ns, poses_[0].back().t_ns);
  const double dt = s.t_ns == kStateTimeUnset ? 0.0 : S(now - s.t_ns);
  out.offset_s = s.x(0) + s.x(1) * dt;
  const double qr = std::pow(options_.drift_walk_ppm_per_sqrt_s * kPpm, 2);
  const double qt = std::pow(options_.offset_walk_s_per_sqrt_s, 2);
  const double var =
      s.P(0, 0) + 2.0 * dt * s.P(0, 1) + dt * dt * s.P(1, 1) + qr * dt * dt * dt / 3.0 + qt * dt;
  out.std_s = std::sqrt(std::max(0.0, var));
  out.drift_ppm = s.x(1) / kPpm;
  out.drift_std_ppm = std::sqrt(std::max(0.0, s.P(1, 1))) / kPpm;
  // Usable once refined by a measurement, while no jump is suspected.
  out.known = s.measurements > 0 && s.outliers == 0;
  return out;
}

int64_t ClockOffsetTracker::MatchingOffsetNs(int i) const {
  const Slave& s = slaves_[i];
  if (!s.initialised) return Ns(s.prior_s);
  return Ns(SlaveOffset(i).offset_s);
}

std::vector<ClockOffsetState> ClockOffsetTracker::SaveState() const {
  std::vector<ClockOffsetState> out(slaves_.size());
  for (size_t i = 0; i < slaves_.size(); ++i) {
    const Slave& s = slaves_[i];
    if (!s.estimated) continue;
    ClockOffsetState& o = out[i];
    o.initialised = s.initialised;
    o.jumps = s.jumps;
    if (!s.initialised) continue;
    o.offset_s = s.x(0);
    o.drift = s.x(1);
    o.covariance = s.P;
    o.t_ns = s.t_ns;
    o.measurements = s.measurements;
  }
  return out;
}

Status ClockOffsetTracker::RestoreState(const std::vector<ClockOffsetState>& states) {
  if (states.size() != slaves_.size()) {
    return Error{"clock offsets: " + std::to_string(states.size()) + " saved, the rig has " +
                 std::to_string(slaves_.size()) + " slaves"};
  }
  for (size_t i = 0; i < states.size(); ++i) {
    const ClockOffsetState& o = states[i];
    if (!std::isfinite(o.offset_s) || !std::isfinite(o.drift) || !o.covariance.allFinite() ||
        o.covariance(0, 0) < 0.0 || o.covariance(1, 1) < 0.0 || o.measurements < 0 || o.jumps < 0) {
      return Error{"clock offset of '" + names_[i + 1] + "': a non-finite or negative value"};
    }
  }
  for (size_t i = 0; i < states.size(); ++i) {
    Slave& s = slaves_[i];
    const ClockOffsetState& o = states[i];
    if (!s.estimated) continue;
    s.jumps = o.jumps;
    s.ever_initialised = o.initialised || o.jumps > 0;
    if (!o.initialised) continue;
    s.initialised = true;
    s.x << o.offset_s, o.drift;
    s.P = o.covariance;
    s.t_ns = o.t_ns;
    s.measurements = o.measurements;
    s.next_from_ns = 0;  // measurements go on from the first master pose after the restart
    s.usable_from_ns = 0;
    s.prior_s = o.offset_s;
  }
  return Status::Ok();
}

void ClockOffsetTracker::FollowClockJump(int i, double prior_s) {
  if (i < 0 || i >= num_slaves()) return;
  Slave& s = slaves_[i];
  if (!s.estimated) return;
  if (s.ever_initialised) ++s.jumps;
  poses_[i + 1].clear();
  s.initialised = false;
  s.since_ns = poses_[0].empty() ? 0 : poses_[0].back().t_ns;
  s.outliers = 0;
  s.measurements = 0;
  s.prior_s = prior_s;
  s.search_s = options_.search_window_s;
  ModuleLogger("calib")->info(
      "time offset of '{}': its clock restarted; re-acquiring the offset within ±{} s of {:.6f} s",
      names_[i + 1], options_.search_window_s, prior_s);
}

void ClockOffsetTracker::FollowMasterClockJump(double step_s) {
  const auto log = ModuleLogger("calib");
  const std::deque<CameraPose>& master = poses_[0];
  // The step is known to within about a frame of the master: the offsets are searched within a
  // few of its σ by the next measurement (a quarter of a frame; no new correlation).
  const int64_t frame = master.size() < 2 ? Ns(0.05)
                                          : (master.back().t_ns - master.front().t_ns) /
                                                static_cast<int64_t>(master.size() - 1);
  const double step_var = std::pow(0.25 * S(frame), 2);
  for (int i = 0; i < num_slaves(); ++i) {
    Slave& s = slaves_[i];
    s.prior_s -= step_s;
    s.outliers = 0;
    s.lag_slave_ns = -1;
    s.since_ns = 0;
    s.next_from_ns = 0;  // measurements go on from the master's first pose on its new clock
    if (!s.estimated) {
      // Given relative to the master's old clock: it no longer holds; estimated from now on,
      // starting at the given value moved by the step.
      const double given = s.x(0);
      s.estimated = true;
      s.x << given - step_s, 0.0;
      s.P.setZero();
      s.P(0, 0) = step_var;
      s.P(1, 1) = std::pow(options_.drift_ppm * kPpm, 2);
      s.t_ns = kStateTimeUnset;  // the start of the first window on the new clock
      s.measurements = 0;
      s.usable_from_ns = 0;
      s.ever_initialised = true;
      s.prior_s = given - step_s;
      log->warn(
          "time offset of '{}': given as {:.6f} s on the master's clock, which restarted; "
          "estimating it from now on, around {:.6f} s",
          names_[i + 1], given, given - step_s);
      continue;
    }
    if (!s.initialised) continue;  // (re)initialising around prior_s, moved above
    s.x(0) -= step_s;
    s.t_ns += Ns(step_s);
    s.P(0, 0) += step_var;
    s.measurements = 0;  // usable again once a measurement confirms the moved offset
    s.usable_from_ns = 0;
  }
  poses_[0].clear();
  log->info(
      "time offsets: the master's clock restarted (step {:.6f} s); every slave's offset moved by "
      "{:.6f} s, to be confirmed by its next measurement",
      step_s, -step_s);
}

}  // namespace rigcal
