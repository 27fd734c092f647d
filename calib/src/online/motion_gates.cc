// SPDX-License-Identifier: Apache-2.0
// The motion gates of the recursive estimator (motion_gates.h).
#include "online/motion_gates.h"

#include <algorithm>
#include <cmath>

#include "models/linear_solvers.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/quaternion.h"

namespace rigcal::internal {
namespace {

// The scale of the motion's segment in the estimate (0: none).
double SegmentScaleOf(const SlaveCalibration& estimate, int segment) {
  double scale = 0.0;
  for (const auto& sc : estimate.scales) {
    if (sc.segment == segment) scale = sc.scale;
  }
  return scale;
}

// Screw-pitch invariant (4.18): the scale the motion measures, C_0·r_0 / C_i·r_i along the
// rotation axes, disagrees with `scale` by more than scale_gate. Motions whose slave
// translation along the axis is within 10x the 3-eps threshold of (4.23) measure nothing.
bool ScaleDisagrees(const RigEstimatorOptions& o, const GateState& state, const MotionData& md,
                    double scale) {
  const double vi = md.qi.tail<3>().norm(), v0 = md.q0.tail<3>().norm();
  const double delta = 30.0 * 1e-3 * std::sqrt(state.ci_sq.value);  // 10x the 3-eps threshold
  if (!(vi > 1e-9 && v0 > 1e-9)) return false;
  const double si = md.Ci.dot(md.qi.tail<3>() / vi);
  if (!(std::abs(si) > delta)) return false;
  const double measured = md.C0.dot(md.q0.tail<3>() / v0) / si;
  return std::abs(measured / scale - 1.0) > o.scale_gate;
}

}  // namespace

GateOutcome GateMotion(const RigEstimatorOptions& o, const GateState& state, const MotionData& md,
                       bool rotating, const SlaveCalibration* estimate) {
  GateOutcome out;
  if (rotating && md.angle0 * kDegPerRad < o.pair_min_angle_deg) {
    out.verdict = GateVerdict::kSmallRotation;
    return out;
  }
  const bool gating = state.accepted_in_model >= o.gate_after_motions && estimate != nullptr;
  out.angle_diff_deg = std::abs(md.angle0 - md.anglei) * kDegPerRad;
  const double angle_gate =
      gating ? std::max(o.angle_gate_floor_deg, o.gate_sigmas * std::sqrt(state.angle_var.value))
             : 4.0 * o.angle_gate_floor_deg;
  if (out.angle_diff_deg > angle_gate) {
    out.verdict = GateVerdict::kAngleMismatch;
    return out;
  }
  if (estimate == nullptr) return out;
  const Similarity& e = estimate->estimate;
  out.r_rot = RotationResidual(md, ToWxyz(e.q));
  const double scale = SegmentScaleOf(*estimate, md.segment);
  if (scale > 0.0) {
    out.r_pos =
        rotating ? PositionResidual(md, e.q, e.C, scale) : TranslationalResidual(md, e.q, scale);
    if (gating && rotating && ScaleDisagrees(o, state, md, scale)) {
      out.verdict = GateVerdict::kScaleMismatch;
      return out;
    }
  }
  if (gating) {
    double worst = rotating ? out.r_rot / std::sqrt(std::max(state.rot_var.value, 1e-300)) : 0.0;
    if (out.r_pos >= 0.0) {
      worst = std::max(worst, out.r_pos / std::sqrt(std::max(state.pos_var.value, 1e-300)));
    }
    if (worst > o.gate_sigmas) {
      out.verdict = GateVerdict::kOutlier;
      return out;
    }
    if (worst > o.huber_sigmas) out.weight = o.huber_sigmas / worst;  // Huber
  }
  return out;
}

void RecordAccepted(const GateOutcome& g, const MotionData& md, bool have_estimate, GateState* s) {
  s->gate_rejections_in_row = 0;
  s->angle_var.Add(g.angle_diff_deg * g.angle_diff_deg);
  s->ci_sq.Add(md.Ci.squaredNorm());
  if (have_estimate) {
    s->rot_var.Add(g.r_rot * g.r_rot);
    if (g.r_pos >= 0.0) s->pos_var.Add(g.r_pos * g.r_pos);
  }
  ++s->accepted_in_model;
}

void RecordResidualRejection(const RigEstimatorOptions& o, const std::string& slave_name,
                             GateState* s) {
  if (++s->gate_rejections_in_row < o.gate_after_motions) return;
  ModuleLogger("calib")->info(
      "slave '{}': {} motions in a row contradict the estimate; residual gating restarts",
      slave_name, s->gate_rejections_in_row);
  s->gate_rejections_in_row = 0;
  RestartResidualGating(s);
}

void RestartResidualGating(GateState* s) {
  s->accepted_in_model = 0;
  s->rot_var = {};
  s->pos_var = {};
}

}  // namespace rigcal::internal
