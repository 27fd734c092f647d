// SPDX-License-Identifier: Apache-2.0
// Clock offset of a free-running camera: angular-speed correlation, then the hand-eye
// rotation residuals (batch) or the rotation-angle residuals (online) minimised over the offset.
#include "rigcal/calib/clock_offset.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/pose_interpolation.h"

namespace rigcal {
namespace {

constexpr size_t kMinPoses = 10;
constexpr double kMaxGapIntervals = 3.0;

double Seconds(int64_t t_ns, int64_t origin_ns) {
  return static_cast<double>(t_ns - origin_ns) * 1e-9;
}

// |ω| at the midpoints of consecutive poses (same segment, no gap), times in seconds from
// `origin_ns` on the trajectory's own clock.
struct AngularSpeed {
  std::vector<double> t;
  std::vector<double> w;
  double max_gap = 0.0;

  // Linear interpolation between neighbouring samples no further apart than max_gap.
  std::optional<double> At(double time) const {
    const auto it = std::lower_bound(t.begin(), t.end(), time);
    if (it == t.end()) return std::nullopt;
    const auto hi = static_cast<size_t>(it - t.begin());
    if (t[hi] == time) return w[hi];
    if (hi == 0 || t[hi] - t[hi - 1] > max_gap) return std::nullopt;
    const double f = (time - t[hi - 1]) / (t[hi] - t[hi - 1]);
    return (1.0 - f) * w[hi - 1] + f * w[hi];
  }
};

// Caps the samples beyond kSpikeMads robust σ (1.4826 MAD) above the median: a pose glitch, or a
// jump of the clock between two poses (the rotation of a second attributed to one frame
// interval), would otherwise dominate the correlation.
constexpr double kSpikeMads = 6.0;
void ClipSpikes(std::vector<double>* w) {
  if (w->size() < 5) return;
  std::vector<double> sorted = *w;
  const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  const double median = *mid;
  for (double& v : sorted) v = std::abs(v - median);
  std::nth_element(sorted.begin(), mid, sorted.end());
  const double mad = *mid;
  if (!(mad > 0.0)) return;
  const double cap = median + kSpikeMads * 1.4826 * mad;
  for (double& v : *w) v = std::min(v, cap);
}

AngularSpeed AngularSpeedOf(const TimedTrajectory& tr, int64_t origin_ns) {
  AngularSpeed out;
  const double interval = static_cast<double>(MedianInterval(tr.t_ns)) * 1e-9;
  out.max_gap = kMaxGapIntervals * interval;
  for (size_t i = 0; i + 1 < tr.size(); ++i) {
    const double dt = static_cast<double>(tr.t_ns[i + 1] - tr.t_ns[i]) * 1e-9;
    const bool same_segment = tr.segment.empty() || tr.segment[i] == tr.segment[i + 1];
    if (dt <= 0.0 || dt > out.max_gap || !same_segment) continue;
    out.t.push_back(0.5 * (Seconds(tr.t_ns[i], origin_ns) + Seconds(tr.t_ns[i + 1], origin_ns)));
    out.w.push_back(RotationAngle(tr.poses[i].q.conjugate() * tr.poses[i + 1].q) / dt);
  }
  ClipSpikes(&out.w);
  return out;
}

// Pearson correlation of the pairs; nullopt with fewer than 3 pairs or no variance.
std::optional<double> Correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const auto n = static_cast<double>(a.size());
  if (a.size() < 3) return std::nullopt;
  double ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
  ma /= n, mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  if (saa <= 0.0 || sbb <= 0.0) return std::nullopt;
  return sab / std::sqrt(saa * sbb);
}

std::string Named(const TimedTrajectory& slave) { return "time offset of '" + slave.name + "': "; }

// Golden-section search of the minimum of `cost` on [lo, hi], to `tolerance`.
template <typename Cost>
double GoldenSection(const Cost& cost, double lo, double hi, double tolerance) {
  constexpr double kInvPhi = 0.6180339887498949;
  double x1 = hi - kInvPhi * (hi - lo);
  double x2 = lo + kInvPhi * (hi - lo);
  double f1 = cost(x1);
  double f2 = cost(x2);
  while (hi - lo > tolerance) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - kInvPhi * (hi - lo), f1 = cost(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + kInvPhi * (hi - lo), f2 = cost(x2);
    }
  }
  return 0.5 * (lo + hi);
}

// Motions of the rig between master-clock instants u and u + span whose start phases within a
// master frame interval cycle through kPhases evenly spaced values, both cameras interpolated
// there (InterpolatePose). Comparing the master at its own frames with the slave interpolated
// at frame + τ would make the expected cost depend on τ through the interpolation alone: an
// interpolated pose averages the noise of its neighbours (a quarter to a third less variance
// midway), so the cost is lowest between frames whatever the truth (on a slow drive, errors of
// up to a frame at a σ of 2 ms). With the phases spread evenly, both cameras' interpolation
// fractions are spread evenly over a frame at every τ, and the expected noise does not depend
// on τ (to 1/kPhases² of its swing).
constexpr int kPhases = 8;

struct MotionSet {
  std::vector<int64_t> from_ns, to_ns;  // master clock
  std::vector<Eigen::Quaterniond> a;    // master rotation from `from` to `to` (its frame)
  int64_t slave_max_gap_ns = 0;
  int64_t reach_ns = 0;  // instants closer than this share a pose of either camera
};

// Disjoint motions in [from_ns, to_ns], consecutive starts a span and 1/kPhases of a master frame
// apart, whose slave ends can be interpolated in one segment at every offset of `taus`.
MotionSet StaggeredMotions(const TimedTrajectory& master, const TimedTrajectory& slave,
                           int64_t from_ns, int64_t to_ns, int64_t span_ns,
                           const std::vector<double>& taus) {
  MotionSet out;
  const int64_t master_interval = MedianInterval(master.t_ns);
  const int64_t slave_interval = MedianInterval(slave.t_ns);
  const auto gap = [](int64_t interval) {
    return static_cast<int64_t>(kMaxGapIntervals * static_cast<double>(interval));
  };
  out.slave_max_gap_ns = gap(slave_interval);
  out.reach_ns = 2 * std::max(master_interval, slave_interval);
  const int64_t phase_ns = master_interval / kPhases;
  auto add = [&](int64_t u, int phase) {
    const int64_t b = u + phase * phase_ns;
    const int64_t e = b + span_ns;
    const auto ma = InterpolatePose(master, b, gap(master_interval));
    const auto mb = InterpolatePose(master, e, gap(master_interval));
    if (!ma || !mb || ma->segment != mb->segment) return;
    for (const double tau : taus) {
      const auto sa = InterpolatePose(slave, b + std::llround(tau * 1e9), out.slave_max_gap_ns);
      const auto sb = InterpolatePose(slave, e + std::llround(tau * 1e9), out.slave_max_gap_ns);
      if (!sa || !sb || sa->segment != sb->segment) return;
    }
    out.from_ns.push_back(b);
    out.to_ns.push_back(e);
    out.a.push_back(ma->pose.q.conjugate() * mb->pose.q);
  };
  // span is a whole number of master frames: the k-th start lies k/kPhases of a frame on.
  for (int64_t u = from_ns; u + span_ns <= to_ns; u += span_ns + phase_ns) add(u, 0);
  return out;
}

// The slave's rotation over motion j at offset tau (nullopt where it cannot be interpolated).
std::optional<Eigen::Quaterniond> SlaveMotion(const TimedTrajectory& slave, const MotionSet& m,
                                              size_t j, double tau) {
  const int64_t shift = std::llround(tau * 1e9);
  const auto a = InterpolatePose(slave, m.from_ns[j] + shift, m.slave_max_gap_ns);
  const auto b = InterpolatePose(slave, m.to_ns[j] + shift, m.slave_max_gap_ns);
  if (!a || !b) return std::nullopt;
  return a->pose.q.conjugate() * b->pose.q;
}

// σ of the τ minimising Σ|r_j(τ)|², from the Gauss-Newton step τ̂ - τ ≈ -Σ g_j / Σ|J_j|² (g_j =
// J_j·r_j): Var = Σ over pairs of motions that share a pose (ends closer than m.reach_ns) or
// overlap in time (drift) of g_j g_k, over (Σ|J_j|²)² (a sandwich: no assumption on the
// noise's level, whiteness or how the motions share poses). Falls back to the pairs j = k when
// the sum is not positive. NaN with fewer than 5 motions.
double SandwichStd(const MotionSet& m, const std::vector<size_t>& used,
                   const std::vector<double>& g, double jtj) {
  if (used.size() < 5 || !(jtj > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  double var = 0.0;
  double diagonal = 0.0;
  for (size_t x = 0; x < used.size(); ++x) {
    diagonal += g[x] * g[x];
    var += g[x] * g[x];
    const size_t j = used[x];
    for (size_t y = x + 1; y < used.size(); ++y) {
      const size_t k = used[y];
      if (m.from_ns[k] - m.reach_ns > m.to_ns[j] + m.reach_ns) break;  // starts are increasing
      var += 2.0 * g[x] * g[y];
    }
  }
  // Residuals at the estimate are smaller than the noise by the fitted parameter's share.
  const double n = static_cast<double>(used.size());
  return std::sqrt((var > 0.0 ? var : diagonal) * n / (n - 1.0)) / jtj;
}

}  // namespace

Expected<TimeOffsetEstimate> CorrelateAngularSpeed(const TimedTrajectory& master,
                                                   const TimedTrajectory& slave,
                                                   const TimeOffsetOptions& options) {
  for (const TimedTrajectory* t : {&master, &slave}) {
    if (t->size() < kMinPoses) {
      return Error{Named(slave) + "camera '" + t->name + "' has " + std::to_string(t->size()) +
                   " poses, at least " + std::to_string(kMinPoses) + " needed"};
    }
  }
  const int64_t origin = master.t_ns.front();
  const AngularSpeed wm = AngularSpeedOf(master, origin);
  const AngularSpeed ws = AngularSpeedOf(slave, origin);
  if (wm.t.size() < 3 || ws.t.size() < 3) {
    return Error{Named(slave) + "too few consecutive poses without a gap for angular speeds"};
  }
  const double h = 0.5 * std::min(wm.max_gap, ws.max_gap) / kMaxGapIntervals;
  const auto lags = static_cast<int>(std::ceil(options.search_window_s / h));
  // The master's |ω| on the grid.
  std::vector<double> grid_t;
  std::vector<double> grid_w;
  for (double t = wm.t.front(); t <= wm.t.back(); t += h) {
    if (const auto w = wm.At(t)) grid_t.push_back(t), grid_w.push_back(*w);
  }
  std::vector<std::optional<double>> c(2 * static_cast<size_t>(lags) + 1);
  std::vector<double> a, b;
  for (int i = -lags; i <= lags; ++i) {
    const double tau = options.center_s + i * h;
    a.clear(), b.clear();
    for (size_t g = 0; g < grid_t.size(); ++g) {
      if (const auto w = ws.At(grid_t[g] + tau)) a.push_back(grid_w[g]), b.push_back(*w);
    }
    if (static_cast<double>(a.size()) * h < options.min_overlap_s) continue;
    c[static_cast<size_t>(i + lags)] = Correlation(a, b);
  }
  std::optional<size_t> best;
  for (size_t i = 0; i < c.size(); ++i) {
    if (c[i] && (!best || *c[i] > *c[*best])) best = i;
  }
  if (!best) {
    return Error{Named(slave) + "master and slave overlap by less than " +
                 SignificantText(options.min_overlap_s, 6) + " s at every offset within " +
                 (options.center_s == 0.0 ? "" : SignificantText(options.center_s, 9) + " ") + "±" +
                 SignificantText(options.search_window_s, 6) + " s (master " +
                 SignificantText(Seconds(master.t_ns.front(), 0), 12) + ".." +
                 SignificantText(Seconds(master.t_ns.back(), 0), 12) + " s, slave " +
                 SignificantText(Seconds(slave.t_ns.front(), 0), 12) + ".." +
                 SignificantText(Seconds(slave.t_ns.back(), 0), 12) + " s)"};
  }
  TimeOffsetEstimate out;
  out.correlation = *c[*best];
  double delta = 0.0;
  if (*best > 0 && *best + 1 < c.size() && c[*best - 1] && c[*best + 1]) {
    const double lo = *c[*best - 1], mid = *c[*best], hi = *c[*best + 1];
    const double denominator = lo - 2.0 * mid + hi;
    if (denominator < 0.0) delta = std::clamp(0.5 * (lo - hi) / denominator, -0.5, 0.5);
  }
  out.offset_s = options.center_s + (static_cast<double>(*best) - lags + delta) * h;
  return out;
}

namespace {

// The straight-line fits of RefineAround's residuals around an offset: per used motion j,
// g_j = J_j·r_j (slope J_j over the window, r_j its mean), and Σ|J_j|². `jtj_signal` estimates
// the smooth signal's share of Σ|J_j|²: Σ J_left·J_right, the slopes of the window's two halves
// (the samples left and right of the centre), whose noises come from different poses, so that
// the product's expectation is the signal's slope squared alone. Σ|J_j|² adds the noise's own
// slope, which (errors in the variables) makes a σ from it too small where the noise's slope
// rivals the signal's.
struct LineFits {
  std::vector<size_t> used;
  std::vector<double> g;
  double jtj = 0.0;
  double jtj_signal = 0.0;
};

// One step of the straight-line fit of RefineAround: each residual fitted over ±2 frames (h)
// around *offset_s in half frames, the offset moved by -Σ J_j·r_j / Σ|J_j|² (at most h). False
// with fewer than 5 motions.
template <typename Residual>
bool FitAround(const MotionSet& m, const Residual& residual, double h, double* offset_s,
               LineFits* fits) {
  constexpr int kSteps = 4;  // per side
  constexpr double kN = 2.0 * kSteps + 1.0;
  constexpr double kKK = kSteps * (kSteps + 1.0) * (2.0 * kSteps + 1.0) / 3.0;  // Σ k²
  // A half's samples k = 1..kSteps about their middle (kSteps + 1) / 2: Σ (k - middle)².
  constexpr double kHalfMiddle = (kSteps + 1.0) / 2.0;
  constexpr double kHalfKK = kSteps * (kSteps * kSteps - 1.0) / 12.0;
  *fits = LineFits{};
  double step = 0.0;
  for (size_t j = 0; j < m.a.size(); ++j) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), slope = Eigen::Vector3d::Zero();
    Eigen::Vector3d left = Eigen::Vector3d::Zero(), right = Eigen::Vector3d::Zero();
    bool ok = true;
    for (int k = -kSteps; k <= kSteps && ok; ++k) {
      const auto r = residual(j, *offset_s + 0.5 * k * h);
      ok = r.has_value();
      if (!ok) break;
      sum += *r, slope += k * *r;
      if (k < 0) left += (k + kHalfMiddle) * *r;
      if (k > 0) right += (k - kHalfMiddle) * *r;
    }
    if (!ok) continue;
    const Eigen::Vector3d jac = slope / (kKK * 0.5 * h);
    fits->jtj += jac.squaredNorm();
    fits->jtj_signal += left.dot(right) / std::pow(kHalfKK * 0.5 * h, 2);
    fits->g.push_back(jac.dot(sum / kN));
    step += fits->g.back();
    fits->used.push_back(j);
  }
  if (fits->used.size() < 5 || !(fits->jtj > 0.0)) return false;
  *offset_s -= std::clamp(step / fits->jtj, -h, h);
  return true;
}

// How much the slopes in the σ's denominator exceed the signal's (at least 1; 0 when the fits
// find no signal slope at all). The local slopes (`local_jtj`, central differences at the cost's
// minimum) include the cost's wiggles on the scale of a frame, which the fit's slopes over ±2
// frames there (`fit_jtj_at_minimum`) average out; the fit's slopes include what noise is left
// (LineFits::jtj_signal).
double SlopeInflation(bool from_fit, const LineFits& fits, double local_jtj,
                      double fit_jtj_at_minimum) {
  if (from_fit) return fits.jtj_signal > 0.0 ? std::max(1.0, fits.jtj / fits.jtj_signal) : 0.0;
  return fit_jtj_at_minimum > 0.0 ? std::max(1.0, local_jtj / fit_jtj_at_minimum) : 1.0;
}

// RefineTimeOffset within [center - h, center + h] (h the slave's frame interval); nullopt with
// fewer than 5 motions. `at_bound`: the minimum lies at an end of the interval.
std::optional<TimeOffsetEstimate> RefineAround(const TimedTrajectory& master,
                                               const TimedTrajectory& slave,
                                               const Eigen::Quaterniond& x, double center_s,
                                               const TimeOffsetOptions& options, bool* at_bound) {
  const int64_t master_interval = MedianInterval(master.t_ns);
  const double h = static_cast<double>(MedianInterval(slave.t_ns)) * 1e-9;
  const int64_t span_ns = std::max<int64_t>(1, std::llround(options.motion_span_s * 1e9 /
                                                            static_cast<double>(master_interval))) *
                          master_interval;
  const MotionSet m = StaggeredMotions(master, slave, master.t_ns.front(), master.t_ns.back(),
                                       span_ns, {center_s - 1.1 * h, center_s, center_s + 1.1 * h});
  if (m.a.size() < 5) return std::nullopt;
  // Rotation-vector residuals of A X = X B(τ) (empty where the slave cannot be interpolated).
  auto residual = [&](size_t j, double tau) -> std::optional<Eigen::Vector3d> {
    const auto b = SlaveMotion(slave, m, j, tau);
    if (!b) return std::nullopt;
    const Eigen::AngleAxisd e((m.a[j] * x).conjugate() * (x * *b));
    return Eigen::Vector3d(e.angle() * e.axis());
  };
  auto cost = [&](double tau) {
    double sum = 0.0;
    for (size_t j = 0; j < m.a.size(); ++j) {
      if (const auto r = residual(j, tau)) sum += r->squaredNorm();
    }
    return sum;
  };
  TimeOffsetEstimate out;
  out.offset_s = GoldenSection(cost, center_s - h, center_s + h, 1e-6);
  *at_bound = std::abs(out.offset_s - center_s) > 0.98 * h;
  // The cost is the smooth signal plus the noise of the interpolated poses, which wiggles on the
  // scale of a frame. Where the signal's slope dominates, the minimum stands and its σ comes from
  // the local Jacobians (central differences, SandwichStd). Where the noise's slope adds more
  // than the signal's (slow drives, noisy poses: Σ|J|² locally over twice that of the fit below),
  // the minimum and its σ are taken from each residual's straight-line fit over ±2 frames around
  // it (slope J_j, value r_j at the centre): τ = centre - Σ J_j·r_j / Σ|J_j|², twice.
  std::vector<size_t> used;
  std::vector<double> g;
  double jtj = 0.0;
  const double e = std::max(1e-4, 0.02 * h);
  for (size_t j = 0; j < m.a.size(); ++j) {
    const auto r0 = residual(j, out.offset_s);
    const auto rp = residual(j, out.offset_s + e);
    const auto rm = residual(j, out.offset_s - e);
    if (!r0 || !rp || !rm) continue;
    const Eigen::Vector3d jac = (*rp - *rm) / (2.0 * e);
    jtj += jac.squaredNorm();
    g.push_back(jac.dot(*r0));
    used.push_back(j);
  }
  TimeOffsetEstimate fitted = out;
  LineFits fits;
  double fit_jtj_at_minimum = 0.0;  // the first fit's, centred on the cost's minimum
  for (int pass = 0; pass < 2; ++pass) {
    if (!FitAround(m, residual, h, &fitted.offset_s, &fits)) break;
    if (pass == 0) fit_jtj_at_minimum = fits.jtj;
    if (pass == 0 && !(jtj > 2.0 * fits.jtj)) break;  // the signal's slope dominates
  }
  const bool from_fit = jtj > 2.0 * fits.jtj && fits.used.size() >= 5;
  const double inflation = SlopeInflation(from_fit, fits, jtj, fit_jtj_at_minimum);
  if (from_fit) {
    out.offset_s = fitted.offset_s;
    used = fits.used, g = fits.g, jtj = fits.jtj;
  }
  out.motions = static_cast<int>(used.size());
  // Without a signal slope the offset is known to the searched interval only (uniform, ±h).
  if (used.size() >= 5) {
    out.std_s = inflation > 0.0 ? inflation * SandwichStd(m, used, g, jtj) : h / std::sqrt(3.0);
  }
  return out;
}

}  // namespace

TimeOffsetEstimate RefineTimeOffset(const TimedTrajectory& master, const TimedTrajectory& slave,
                                    const Eigen::Quaterniond& master_from_slave,
                                    const TimeOffsetEstimate& initial,
                                    const TimeOffsetOptions& options) {
  if (MedianInterval(master.t_ns) <= 0 || MedianInterval(slave.t_ns) <= 0) return initial;
  // The correlation's peak can be frames off on a slow drive with noisy poses: a minimum at an
  // end of the searched interval moves the interval there, at most kRecentre times.
  constexpr int kRecentre = 6;
  double center = initial.offset_s;
  for (int round = 0; round <= kRecentre; ++round) {
    bool at_bound = false;
    const auto refined = RefineAround(master, slave, master_from_slave, center, options, &at_bound);
    if (!refined) return initial;
    if (!at_bound || round == kRecentre) {
      TimeOffsetEstimate out = *refined;
      out.correlation = initial.correlation;
      return out;
    }
    center = refined->offset_s;
  }
  return initial;
}

namespace {

// σ of MeasureOffsetFromAngles's τ with the residuals' correlation over the motions (one per
// master frame: motions k and k + span share a pose, overlapping ones the drift between them):
// Var = Σ_k Σ_l J_k J_(k+l) γ(l) / (Σ J_k²)², γ(l) the residuals' autocovariance at lag l <=
// `max_lag` pooled over the window (a sandwich of single products would rest on the window's two
// or three independent stretches, too noisy for the Kalman filter's weights). `starts`: the
// motions' first master frames; r, jac: residuals and Jacobians (NaN: not formed); `naive`: the
// variance without correlation, taken when the sum is not positive.
double AutocovarianceStd(const std::vector<size_t>& starts, const std::vector<double>& r,
                         const std::vector<double>& jac, size_t max_lag, double jtj, double naive) {
  double var = 0.0;
  int n = 0;
  for (const double j : jac) n += std::isfinite(j);
  for (size_t lag = 0; lag <= max_lag; ++lag) {
    double gamma = 0.0, jj = 0.0;
    int pairs = 0;
    for (size_t i = 0; i + lag < r.size(); ++i) {
      const size_t k = i + lag;
      if (!std::isfinite(jac[i]) || !std::isfinite(jac[k]) || starts[k] - starts[i] != lag)
        continue;
      gamma += r[i] * r[k];
      jj += jac[i] * jac[k];
      ++pairs;
    }
    if (pairs > 0) var += (lag == 0 ? 1.0 : 2.0) * jj * gamma / pairs;
  }
  return std::sqrt(var > 0.0 ? var * n / (n - 1.0) / (jtj * jtj) : naive);
}

}  // namespace

std::optional<AngleOffsetMeasurement> MeasureOffsetFromAngles(const TimedTrajectory& master,
                                                              const TimedTrajectory& slave,
                                                              int64_t from_ns, int64_t to_ns,
                                                              double center_s, double half_width_s,
                                                              double motion_span_s) {
  const int64_t master_interval = MedianInterval(master.t_ns);
  const int64_t slave_interval = MedianInterval(slave.t_ns);
  if (master_interval <= 0 || slave_interval <= 0 || !(half_width_s > 0.0)) return std::nullopt;
  const auto max_gap_ns =
      static_cast<int64_t>(kMaxGapIntervals * static_cast<double>(slave_interval));
  const auto span = static_cast<size_t>(std::max<int64_t>(
      1, std::llround(motion_span_s * 1e9 / static_cast<double>(master_interval))));
  auto segment_of = [&](size_t k) { return master.segment.empty() ? 0 : master.segment[k]; };
  // Motion k runs from master frame k to k + span, both ends moved on by (k mod kPhases) /
  // kPhases of a master frame, both cameras interpolated there: the interpolation fractions
  // are spread over a frame at every τ (as in RefineTimeOffset).
  const int64_t master_gap_ns =
      static_cast<int64_t>(kMaxGapIntervals * static_cast<double>(master_interval));
  auto shift_of = [&](size_t k) {
    return static_cast<int64_t>(k % kPhases) * (master_interval / kPhases);
  };
  auto slave_at = [&](size_t k, int64_t shift, double tau) {
    return InterpolatePose(slave, master.t_ns[k] + shift + std::llround(tau * 1e9), max_gap_ns);
  };
  // Motions starting in [from_ns, to_ns) whose slave ends can be interpolated over the whole
  // searched interval, with the master's rotation angle.
  std::vector<size_t> starts;
  std::vector<int64_t> shifts;
  std::vector<double> master_angle;
  const auto first = static_cast<size_t>(
      std::lower_bound(master.t_ns.begin(), master.t_ns.end(), from_ns) - master.t_ns.begin());
  for (size_t k = first; k + span < master.size() && master.t_ns[k] < to_ns; ++k) {
    if (segment_of(k) != segment_of(k + span)) continue;
    const int64_t shift = shift_of(k);
    const auto ma = InterpolatePose(master, master.t_ns[k] + shift, master_gap_ns);
    const auto mb = InterpolatePose(master, master.t_ns[k + span] + shift, master_gap_ns);
    bool valid = ma && mb && ma->segment == mb->segment;
    for (const double tau : {center_s - half_width_s, center_s + half_width_s}) {
      const auto a = slave_at(k, shift, tau);
      const auto b = slave_at(k + span, shift, tau);
      valid = valid && a && b && a->segment == b->segment;
    }
    if (!valid) continue;
    starts.push_back(k);
    shifts.push_back(shift);
    master_angle.push_back(RotationAngle(ma->pose.q.conjugate() * mb->pose.q));
  }
  if (starts.size() < 5) return std::nullopt;
  auto residuals = [&](double tau, std::vector<double>* r) {
    r->assign(starts.size(), std::numeric_limits<double>::quiet_NaN());
    for (size_t i = 0; i < starts.size(); ++i) {
      const auto a = slave_at(starts[i], shifts[i], tau);
      const auto b = slave_at(starts[i] + span, shifts[i], tau);
      if (a && b) (*r)[i] = master_angle[i] - RotationAngle(a->pose.q.conjugate() * b->pose.q);
    }
  };
  std::vector<double> scratch;
  auto cost = [&](double tau) {
    residuals(tau, &scratch);
    double sum = 0.0;
    for (const double v : scratch) sum += std::isfinite(v) ? v * v : 0.0;
    return sum;
  };
  const double lo = center_s - half_width_s;
  const double hi = center_s + half_width_s;
  AngleOffsetMeasurement out;
  out.offset_s = GoldenSection(cost, lo, hi, 1e-7);
  out.at_bound = out.offset_s - lo < 0.02 * half_width_s || hi - out.offset_s < 0.02 * half_width_s;
  const double e = std::max(1e-5, 0.01 * static_cast<double>(slave_interval) * 1e-9);
  std::vector<double> r0, rp, rm;
  residuals(out.offset_s, &r0);
  residuals(out.offset_s + e, &rp);
  residuals(out.offset_s - e, &rm);
  std::vector<double> jac(r0.size(), std::numeric_limits<double>::quiet_NaN());
  double jtj = 0.0;
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < r0.size(); ++i) {
    if (!std::isfinite(r0[i]) || !std::isfinite(rp[i]) || !std::isfinite(rm[i])) continue;
    jac[i] = (rp[i] - rm[i]) / (2.0 * e);
    jtj += jac[i] * jac[i];
    sum += r0[i] * r0[i];
    ++n;
  }
  out.motions = n;
  if (n < 5 || !(jtj > 0.0)) return std::nullopt;
  out.rms_rad = std::sqrt(sum / n);
  out.std_s = AutocovarianceStd(starts, r0, jac, span + 2, jtj, sum / (n - 1.0) / jtj);
  return out;
}

}  // namespace rigcal
