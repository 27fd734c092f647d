// SPDX-License-Identifier: Apache-2.0
// Clock offset of a free-running camera: angular-speed correlation, then the hand-eye
// rotation residuals (batch) or the rotation-angle residuals (online) minimised over the offset.
#include "rigcal/calib/clock_offset.h"

#include <algorithm>
#include <cmath>
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

TimeOffsetEstimate RefineTimeOffset(const TimedTrajectory& master, const TimedTrajectory& slave,
                                    const Eigen::Quaterniond& master_from_slave,
                                    const TimeOffsetEstimate& initial,
                                    const TimeOffsetOptions& options) {
  const Eigen::Quaterniond& x = master_from_slave;  // X of the hand-eye residuals A X = X B
  const int64_t master_interval = MedianInterval(master.t_ns);
  const int64_t slave_interval = MedianInterval(slave.t_ns);
  if (master_interval <= 0 || slave_interval <= 0) return initial;
  const auto max_gap_ns =
      static_cast<int64_t>(kMaxGapIntervals * static_cast<double>(slave_interval));
  const double h = static_cast<double>(slave_interval) * 1e-9;
  const auto span = static_cast<size_t>(std::max<int64_t>(
      1, std::llround(options.motion_span_s * 1e9 / static_cast<double>(master_interval))));
  auto segment_of = [&](size_t k) { return master.segment.empty() ? 0 : master.segment[k]; };
  auto slave_at = [&](size_t k, double tau) {
    return InterpolatePose(slave, master.t_ns[k] + std::llround(tau * 1e9), max_gap_ns);
  };
  // Motions (k, k + span), non-overlapping, valid over the whole search interval.
  std::vector<size_t> starts;
  for (size_t k = 0; k + span < master.size(); k += span) {
    if (segment_of(k) != segment_of(k + span)) continue;
    bool valid = true;
    for (const double tau :
         {initial.offset_s - 1.1 * h, initial.offset_s, initial.offset_s + 1.1 * h}) {
      const auto a = slave_at(k, tau);
      const auto b = slave_at(k + span, tau);
      valid = valid && a && b && a->segment == b->segment;
    }
    if (valid) starts.push_back(k);
  }
  if (starts.size() < 5) return initial;
  // Rotation-vector residuals of A X = X B at offset tau (empty entries where the slave pose
  // cannot be interpolated).
  auto residuals = [&](double tau) {
    std::vector<std::optional<Eigen::Vector3d>> r;
    r.reserve(starts.size());
    for (const size_t k : starts) {
      const auto a = slave_at(k, tau);
      const auto b = slave_at(k + span, tau);
      if (!a || !b) {
        r.emplace_back();
        continue;
      }
      const Eigen::Quaterniond A = master.poses[k].q.conjugate() * master.poses[k + span].q;
      const Eigen::Quaterniond B = a->pose.q.conjugate() * b->pose.q;
      const Eigen::AngleAxisd e((A * x).conjugate() * (x * B));
      r.emplace_back(e.angle() * e.axis());
    }
    return r;
  };
  auto cost = [&](double tau) {
    double sum = 0.0;
    for (const auto& r : residuals(tau)) sum += r ? r->squaredNorm() : 0.0;
    return sum;
  };
  TimeOffsetEstimate out = initial;
  out.offset_s = GoldenSection(cost, initial.offset_s - h, initial.offset_s + h, 1e-6);
  // σ from Gauss-Newton: central differences of the residuals.
  const double e = std::max(1e-4, 0.02 * h);
  const auto r0 = residuals(out.offset_s);
  const auto rp = residuals(out.offset_s + e);
  const auto rm = residuals(out.offset_s - e);
  double jtj = 0.0;
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < r0.size(); ++i) {
    if (!r0[i] || !rp[i] || !rm[i]) continue;
    jtj += ((*rp[i] - *rm[i]) / (2.0 * e)).squaredNorm();
    sum += r0[i]->squaredNorm();
    ++n;
  }
  out.motions = n;
  if (n >= 5 && jtj > 0.0) out.std_s = std::sqrt(sum / (3.0 * n - 1.0) / jtj);
  return out;
}

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
  auto slave_at = [&](size_t k, double tau) {
    return InterpolatePose(slave, master.t_ns[k] + std::llround(tau * 1e9), max_gap_ns);
  };
  // Motions (k, k + span) starting in [from_ns, to_ns) whose slave ends can be interpolated
  // over the whole searched interval, with the master's rotation angle.
  std::vector<size_t> starts;
  std::vector<double> master_angle;
  const auto first = static_cast<size_t>(
      std::lower_bound(master.t_ns.begin(), master.t_ns.end(), from_ns) - master.t_ns.begin());
  for (size_t k = first; k + span < master.size() && master.t_ns[k] < to_ns; ++k) {
    if (segment_of(k) != segment_of(k + span)) continue;
    bool valid = true;
    for (const double tau : {center_s - half_width_s, center_s + half_width_s}) {
      const auto a = slave_at(k, tau);
      const auto b = slave_at(k + span, tau);
      valid = valid && a && b && a->segment == b->segment;
    }
    if (!valid) continue;
    starts.push_back(k);
    master_angle.push_back(RotationAngle(master.poses[k].q.conjugate() * master.poses[k + span].q));
  }
  if (starts.size() < 5) return std::nullopt;
  auto residuals = [&](double tau, std::vector<double>* r) {
    r->assign(starts.size(), std::numeric_limits<double>::quiet_NaN());
    for (size_t i = 0; i < starts.size(); ++i) {
      const auto a = slave_at(starts[i], tau);
      const auto b = slave_at(starts[i] + span, tau);
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
  double jtj = 0.0;
  double sum = 0.0;
  int n = 0;
  for (size_t i = 0; i < r0.size(); ++i) {
    if (!std::isfinite(r0[i]) || !std::isfinite(rp[i]) || !std::isfinite(rm[i])) continue;
    const double j = (rp[i] - rm[i]) / (2.0 * e);
    jtj += j * j;
    sum += r0[i] * r0[i];
    ++n;
  }
  out.motions = n;
  if (n < 5) return std::nullopt;
  out.rms_rad = std::sqrt(sum / n);
  // Every pose ends one motion and starts another: the residuals of motions k and k + span
  // share a pose's error, which doubles the variance of the estimate at most.
  if (jtj > 0.0) out.std_s = std::sqrt(2.0 * sum / (n - 1.0) / jtj);
  return out;
}

}  // namespace rigcal
