// SPDX-License-Identifier: Apache-2.0
#include "estimator_state_ranges.h"

#include <cmath>
#include <sstream>
#include <string>

namespace rigcal::io {
namespace {

constexpr double kPi = 3.14159265358979323846;

Status OutOfRange(const std::string& where, const std::string& field, double value, double lo,
                  double hi) {
  std::ostringstream text;
  text << where << field << " = " << value << " is out of range [" << lo << ", " << hi << "]";
  return Error{text.str()};
}

std::string Number(double v) {
  std::ostringstream text;
  text << v;
  return text.str();
}

Status CheckValue(const std::string& where, const std::string& field, double value, double lo,
                  double hi) {
  if (!std::isfinite(value) || value < lo || value > hi) {
    return OutOfRange(where, field, value, lo, hi);
  }
  return Status::Ok();
}

Status CheckNonNegative(const std::string& where, const std::string& field, double value) {
  return CheckValue(where, field, value, 0.0, kMaxStateMagnitude);
}

Status CheckAny(const std::string& where, const std::string& field, double value) {
  return CheckValue(where, field, value, -kMaxStateMagnitude, kMaxStateMagnitude);
}

template <typename Derived>
Status CheckMatrix(const std::string& where, const std::string& field,
                   const Eigen::MatrixBase<Derived>& m) {
  for (Eigen::Index i = 0; i < m.size(); ++i) {
    if (Status s = CheckAny(where, field + "[" + std::to_string(i) + "]", m.derived().data()[i]);
        !s.ok()) {
      return s;
    }
  }
  return Status::Ok();
}

// Beyond finiteness, what the sums can be for motions that really happened
// (calib/src/models/motion_statistics.cc, MotionStatistics::Add): every motion weighs at most 1
// (the Huber weight) and forgetting only lowers the weights, so the total weight is at most the
// number of motions, and a segment's at most the total; the rotation system M sums w A^T A with
// A = L(q0) - R(qi) of unit quaternions (4.7, |A| <= 2), so its diagonal is not negative and its
// trace at most 16 times the weight. A weight of 9e99 over 40 motions (a hand-edited file with a
// valid checksum) would otherwise make every σ vanish (1e-51 degrees).
Status CheckPhysicalBounds(const std::string& where, const MotionSums& s) {
  constexpr double kRounding = 1e-9;
  const double motions = static_cast<double>(s.motions);
  const double max_weight = motions * (1.0 + kRounding) + kRounding;
  if (s.weight > max_weight) {
    return Error{where + "weight = " + Number(s.weight) + " exceeds motions = " +
                 std::to_string(s.motions) + " (each motion weighs at most 1)"};
  }
  if (s.position_weight && !(*s.position_weight >= 0.0 &&
                             *s.position_weight <= s.weight * (1.0 + kRounding) + kRounding)) {
    return Error{where + "posweight = " + Number(*s.position_weight) +
                 " is not within [0, weight = " + Number(s.weight) + "]"};
  }
  for (const auto& [id, seg] : s.segments) {
    if (seg.weight > s.weight * (1.0 + kRounding) + kRounding) {
      return Error{where + "segment " + std::to_string(id) + ": w = " + Number(seg.weight) +
                   " exceeds the total weight " + Number(s.weight)};
    }
  }
  const double trace = s.rotation.trace();
  if (s.rotation.diagonal().minCoeff() < -kRounding * (1.0 + trace) ||
      trace > 16.0 * s.weight * (1.0 + kRounding) + kRounding) {
    return Error{where + "M: trace " + Number(trace) + " is not within [0, 16 x weight = " +
                 Number(16.0 * s.weight) + "] or its diagonal is negative"};
  }
  return Status::Ok();
}

// The file's labels name the fields (estimator_state_file.cc WriteSums).
Status CheckSums(const std::string& where, const MotionSums& s) {
  // The marginalised constants (c0sqmarg, cplmarg) are differences: rounding may make them
  // slightly negative.
  const std::pair<const char*, double> non_negative[] = {
      {"c0sq", s.c0_sq}, {"weight", s.weight}, {"motions", s.motions}};
  for (const auto& [field, value] : non_negative) {
    if (Status st = CheckNonNegative(where, field, value); !st.ok()) return st;
  }
  if (Status st = CheckValue(where, "maxrot", s.max_rotation, 0.0, 2.0 * kPi); !st.ok()) return st;
  if (Status st = CheckAny(where, "c0sqmarg", s.c0_sq_marg); !st.ok()) return st;
  if (Status st = CheckAny(where, "cplmarg", s.planar.c_marg); !st.ok()) return st;
  for (const Status& st :
       {CheckMatrix(where, "M", s.rotation), CheckMatrix(where, "v00", s.planar.v00),
        CheckMatrix(where, "vii", s.planar.vii), CheckMatrix(where, "v0i", s.planar.v0i),
        CheckMatrix(where, "K", s.planar.k), CheckMatrix(where, "c0c0", s.planar.c0c0),
        CheckMatrix(where, "Hplmarg", s.planar.h_marg),
        CheckMatrix(where, "gplmarg", s.planar.g_marg), CheckMatrix(where, "Hcc", s.h_cc),
        CheckMatrix(where, "gc", s.g_c), CheckMatrix(where, "Sdir", s.s_dir),
        CheckMatrix(where, "Ddir", s.d_dir), CheckMatrix(where, "Hmarg", s.h_marg),
        CheckMatrix(where, "gmarg", s.g_marg)}) {
    if (!st.ok()) return st;
  }
  if (Status st = CheckPhysicalBounds(where, s); !st.ok()) return st;
  for (const auto& [id, seg] : s.segments) {
    const std::string at = where + "segment " + std::to_string(id) + ": ";
    for (const Status& st :
         {CheckMatrix(at, "P", seg.P), CheckMatrix(at, "Q", seg.Q), CheckMatrix(at, "N", seg.N),
          CheckNonNegative(at, "n", seg.n), CheckAny(at, "lc", seg.len_cross),
          CheckNonNegative(at, "ls", seg.len_sq), CheckNonNegative(at, "w", seg.weight),
          CheckAny(at, "scale", seg.last_scale)}) {
      if (!st.ok()) return st;
    }
  }
  for (const auto& [id, scale] : s.closed_scales) {
    if (Status st = CheckAny(where, "closed scale " + std::to_string(id), scale); !st.ok()) {
      return st;
    }
  }
  return Status::Ok();
}

}  // namespace

Status CheckEstimatorStateRanges(const RigEstimatorState& state) {
  for (size_t i = 0; i < state.slaves.size(); ++i) {
    const SlaveEstimatorState& s = state.slaves[i];
    const std::string name = i + 1 < state.cameras.size() ? state.cameras[i + 1] : "?";
    const std::string where = "slave " + name + ": ";
    const MotionCounts& c = s.counts;
    const std::pair<const char*, int> counts[] = {{"counts total", c.total},
                                                  {"counts used", c.used},
                                                  {"counts small_rotation", c.small_rotation},
                                                  {"counts angle_mismatch", c.angle_mismatch},
                                                  {"counts residual_outlier", c.residual_outlier},
                                                  {"noise angle count", s.angle_var.count},
                                                  {"noise rotation count", s.rot_var.count},
                                                  {"noise position count", s.pos_var.count},
                                                  {"noise |C_i|^2 count", s.ci_sq.count}};
    for (const auto& [field, value] : counts) {
      if (Status st = CheckNonNegative(where, field, value); !st.ok()) return st;
    }
    if (c.used > c.total) return OutOfRange(where, "counts used", c.used, 0, c.total);
    const std::pair<const char*, double> variances[] = {{"noise angle", s.angle_var.value},
                                                        {"noise rotation", s.rot_var.value},
                                                        {"noise position", s.pos_var.value},
                                                        {"noise |C_i|^2", s.ci_sq.value}};
    for (const auto& [field, value] : variances) {
      if (Status st = CheckNonNegative(where, field, value); !st.ok()) return st;
    }
    if (Status st = CheckSums(where + "long: ", s.long_stats); !st.ok()) return st;
    if (Status st = CheckSums(where + "short: ", s.short_stats); !st.ok()) return st;
  }
  // Clock offsets: |τ| within a day (the config's limit), |ρ| below 1 % (a clock, not a
  // counter), variances not negative, counts not negative.
  for (size_t i = 0; i < state.clock_offsets.size(); ++i) {
    const ClockOffsetState& c = state.clock_offsets[i];
    const std::string name = i + 1 < state.cameras.size() ? state.cameras[i + 1] : "?";
    const std::string where = "slave " + name + ": clock ";
    for (const Status& st : {CheckValue(where, "offset_s", c.offset_s, -86400.0, 86400.0),
                             CheckValue(where, "drift", c.drift, -0.01, 0.01),
                             CheckNonNegative(where, "P00", c.covariance(0, 0)),
                             CheckAny(where, "P01", c.covariance(0, 1)),
                             CheckNonNegative(where, "P11", c.covariance(1, 1)),
                             CheckNonNegative(where, "measurements", c.measurements),
                             CheckNonNegative(where, "jumps", c.jumps)}) {
      if (!st.ok()) return st;
    }
  }
  return Status::Ok();
}

}  // namespace rigcal::io
