// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/extrinsics_message.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <string>
#include <utility>

#include "message_checker.h"
#include "message_codec.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm {
namespace {

using internal::Checker;
using internal::FormatNumber;
using internal::LayoutWalk;

// The encoding of an unknown standard deviation in slave_extrinsics_t (rot_std_deg, pos_std,
// scale_std, axis_offset_std): a σ that was not computed, whose covariance failed, or that is
// infinite (undetermined).
constexpr double kUnknownStd = -1.0;

// The rules of one slave_extrinsics_t (extrinsics_message.h).
void CheckSlave(const CameraNames& names, slave_extrinsics_t* s, Checker* check) {
  check->CameraName("name", s->name, names, 1, "the rig's slaves");
  check->Text("message", s->message);
  check->Quaternion("q", s->q);
  check->Finite("C", s->C, 3);
  check->Finite("scale", s->scale);
  check->Finite("rot_std_deg", s->rot_std_deg);
  check->Finite("pos_std", s->pos_std, 3);
  check->Finite("scale_std", s->scale_std);
  check->Finite("rotation_eigen_gap", s->rotation_eigen_gap);
  check->Finite("position_min_eigenvalue", s->position_min_eigenvalue);
  check->Finite("axis_spread_deg", s->axis_spread_deg);
  check->Finite("planar_axis", s->planar_axis, 3);
  check->Finite("axis_offset_std", s->axis_offset_std);

  check->InRange<int8_t>("state", s->state, slave_extrinsics_t::STATE_INITIALISING,
                         slave_extrinsics_t::STATE_DECALIBRATED);
  if ((s->flags & ~kKnownFlags) != 0) {
    check->Fail(RejectCause::kOutOfRange, "flags",
                "undefined bits " + std::to_string(s->flags & ~kKnownFlags));
  }
  const bool usable = s->state == slave_extrinsics_t::STATE_USABLE ||
                      s->state == slave_extrinsics_t::STATE_CONVERGED;
  if (usable && !(s->scale > 0.0)) {
    check->Fail(RejectCause::kOutOfRange, "scale",
                FormatNumber(s->scale) + " is not positive in a usable estimate");
  }
  check->AtLeast<int32_t>("segment", s->segment, 0);
  // Standard deviations: >= 0, or exactly -1 = unknown.
  const auto check_std = [&](const std::string& field, double v) {
    if (v != kUnknownStd) check->AtLeast(field, v, 0.0);
  };
  check_std("rot_std_deg", s->rot_std_deg);
  for (int i = 0; i < 3; ++i) check_std("pos_std[" + std::to_string(i) + "]", s->pos_std[i]);
  check_std("scale_std", s->scale_std);
  check->AtLeast<int32_t>("motions_used", s->motions_used, 0);
  check->AtLeast<int32_t>("motions_rejected", s->motions_rejected, 0);
  check->AtLeast("rotation_eigen_gap", s->rotation_eigen_gap, 0.0);
  check->InRange("axis_spread_deg", s->axis_spread_deg, 0.0, 180.0);
  if (s->flags & kWireFlagPlanar) {
    check->Unit("planar_axis", s->planar_axis, 3, RejectCause::kOutOfRange, "planar_axis");
  }
  if ((s->flags & kWireFlagAxisFromPrior) && !(s->flags & kWireFlagPlanar)) {
    check->Fail(RejectCause::kOutOfRange, "flags",
                "FLAG_AXIS_FROM_PRIOR without FLAG_PLANAR_UNOBSERVABLE_AXIS");
  }
  check_std("axis_offset_std", s->axis_offset_std);
  check->InRange<int8_t>("time_offset_source", s->time_offset_source,
                         slave_extrinsics_t::TIME_OFFSET_NONE,
                         slave_extrinsics_t::TIME_OFFSET_ESTIMATED);
  check_std("time_offset_std_s", s->time_offset_std_s);
  check->AtLeast<int32_t>("clock_jumps", s->clock_jumps, 0);
}

// The fields of rig_extrinsics_t.lcm up to num_slaves.
void WalkExtrinsicsLayout(LayoutWalk* walk) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  walk->Fixed("t_ns", 8);
  walk->String("master");
  walk->Fixed("distance_unit", 1);
  const int32_t slaves = walk->Count("num_slaves", slave_extrinsics_t()._getEncodedSizeNoHash());
  // slave_extrinsics_t: name, fixed-size fields, message (an empty string takes 4 + 1 bytes).
  const int64_t fixed = slave_extrinsics_t()._getEncodedSizeNoHash() - 2 * 5;
  for (int32_t i = 0; i < slaves; ++i) {
    const std::string slave = "slaves[" + std::to_string(i) + "]";
    walk->String(slave + ".name");
    walk->Fixed(slave, fixed);
    walk->String(slave + ".message");
  }
}

// The rules of rig_extrinsics_t (extrinsics_message.h) but the version.
void CheckExtrinsics(const CameraNames& names, rig_extrinsics_t* msg, Checker* check) {
  check->Count("num_slaves", msg->num_slaves, msg->slaves.size(), "slaves");
  if (!check->ok()) return;
  check->CameraName("master", msg->master, names, 0, "the rig's cameras");
  if (check->ok() && !names.empty() && msg->master != names[0]) {
    check->Fail(RejectCause::kUnknownCamera, "master",
                "camera '" + msg->master + "' is not the rig's master '" + names[0] + "'");
  }
  check->AtLeast<int64_t>("utime", msg->utime, 0);
  check->AtLeast<int64_t>("t_ns", msg->t_ns, 0);
  check->InRange<int8_t>("distance_unit", msg->distance_unit,
                         rig_extrinsics_t::UNIT_MASTER_ODOMETRY, rig_extrinsics_t::UNIT_METRE);
  check->NamedElements(
      "slaves", &msg->slaves, {msg->master},
      [&](slave_extrinsics_t* s, Checker* nested) { CheckSlave(names, s, nested); });
}

}  // namespace

template <>
struct internal::MessageTraits<rig_extrinsics_t> {
  static constexpr char kTypeName[] = "rig_extrinsics_t";
  static constexpr auto WalkLayout = &WalkExtrinsicsLayout;
  static constexpr auto CheckContent = &CheckExtrinsics;
};

int32_t WireFlagsOf(const SlaveCalibration& slave) {
  int32_t flags = 0;
  if (slave.motion_model == MotionModel::kTranslational || !slave.position_observable) {
    flags |= kWireFlagTranslationalOnly;
  }
  if (slave.observability.planar) {
    flags |= kWireFlagPlanar;
    if (slave.unobservable_from_prior) flags |= kWireFlagAxisFromPrior;
  }
  return flags;
}

int32_t WireFlagsOfFacts(uint32_t facts) {
  int32_t flags = 0;
  if (facts & kFlagPlanar) flags |= kWireFlagPlanar;
  if (facts & kFlagTranslationalOnly) flags |= kWireFlagTranslationalOnly;
  if (facts & kFlagRefined) flags |= kWireFlagRefined;
  return flags;
}

uint32_t FactsOfWireFlags(int32_t wire_flags) {
  uint32_t facts = 0;
  if (wire_flags & kWireFlagPlanar) facts |= kFlagPlanar;
  if (wire_flags & kWireFlagTranslationalOnly) facts |= kFlagTranslationalOnly;
  if (wire_flags & kWireFlagRefined) facts |= kFlagRefined;
  return facts;
}

Expected<slave_extrinsics_t> SlaveCalibrationToLcm(const SlaveCalibration& slave) {
  const bool usable = slave.solved();  // the estimate is defined (the state says if it may be used)
  const std::string who = "slave '" + slave.name + "'";
  const auto or_zero = [](double v) { return std::isfinite(v) ? v : 0.0; };
  const auto std_or_unknown = [](double v) { return std::isfinite(v) ? v : kUnknownStd; };

  slave_extrinsics_t msg;
  msg.name = slave.name;
  Eigen::Quaterniond q = slave.estimate.q;
  Eigen::Vector3d C = slave.estimate.C;
  double scale = slave.estimate.scale;
  int32_t segment = 0;
  double scale_std = std::numeric_limits<double>::quiet_NaN();
  if (!slave.scales.empty()) {
    const SegmentScale& current = *std::max_element(
        slave.scales.begin(), slave.scales.end(),
        [](const SegmentScale& a, const SegmentScale& b) { return a.segment < b.segment; });
    scale = current.scale;
    segment = current.segment;
    scale_std = current.std;
  }
  if (!usable) {  // placeholders for what a failed estimate left undefined
    if (!q.coeffs().allFinite() || q.norm() == 0.0) q = Eigen::Quaterniond::Identity();
    if (!C.allFinite()) C.setZero();
    if (!std::isfinite(scale)) scale = 1.0;
  } else if (!q.coeffs().allFinite() || !C.allFinite() || !std::isfinite(scale)) {
    return Error{who + " is solved (" + ToString(slave.termination) +
                 ") but its estimate is not finite"};
  }
  if (q.norm() > 0.0) q.normalize();
  msg.q[0] = q.w();
  msg.q[1] = q.x();
  msg.q[2] = q.y();
  msg.q[3] = q.z();
  for (int i = 0; i < 3; ++i) msg.C[i] = C[i];
  msg.scale = scale;
  msg.segment = segment;
  msg.rot_std_deg = std_or_unknown(slave.rot_std_deg);
  for (int i = 0; i < 3; ++i) msg.pos_std[i] = std_or_unknown(slave.pos_std[i]);
  msg.scale_std = std_or_unknown(scale_std);
  msg.motions_used = slave.motions.used;
  msg.motions_rejected = slave.motions.rejected();

  const Observability& obs = slave.observability;
  msg.rotation_eigen_gap = or_zero(obs.rotation_eigenvalues[1] - obs.rotation_eigenvalues[0]);
  msg.position_min_eigenvalue = or_zero(obs.position_min_eigenvalue);
  msg.axis_spread_deg = or_zero(obs.axis_spread_deg);
  msg.state = static_cast<int8_t>(slave.state);
  msg.flags = WireFlagsOf(slave);
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  const bool axis_known = obs.planar_axis.allFinite() && obs.planar_axis.norm() > 0.5;
  if (obs.planar && !axis_known) {
    return Error{who + ": observability is planar but planar_axis is not a direction"};
  }
  if (axis_known) axis = obs.planar_axis.normalized();
  for (int i = 0; i < 3; ++i) msg.planar_axis[i] = axis[i];
  msg.axis_offset_std = 0.0;
  if (axis_known && usable && slave.position_observable) {
    if (obs.planar && !slave.unobservable_from_prior) {
      msg.axis_offset_std = kUnknownStd;
    } else if (std::isfinite(slave.axis_offset_std) && slave.axis_offset_std >= 0.0) {
      msg.axis_offset_std = slave.axis_offset_std;
    } else if (!obs.planar) {
      msg.axis_offset_std =
          slave.pos_std.allFinite()
              ? std::sqrt(std::max(0.0, axis.dot(slave.pos_std.cwiseAbs2().asDiagonal() * axis)))
              : kUnknownStd;
    }
  }
  msg.time_offset_source = slave_extrinsics_t::TIME_OFFSET_NONE;
  msg.time_offset_s = 0.0;
  msg.time_offset_std_s = kUnknownStd;
  msg.clock_jumps = 0;
  if (std::isfinite(slave.time_offset_s)) {
    const bool estimated = std::isfinite(slave.time_offset_std_s);
    msg.time_offset_source = estimated ? slave_extrinsics_t::TIME_OFFSET_ESTIMATED
                                       : slave_extrinsics_t::TIME_OFFSET_GIVEN;
    msg.time_offset_s = slave.time_offset_s;
    msg.time_offset_std_s = std_or_unknown(slave.time_offset_std_s);
  }
  msg.message = ToString(slave.termination);
  if (!slave.message.empty()) msg.message += ": " + slave.message;

  Checker check(kExtrinsicsChannel, "slave_extrinsics_t");
  CheckSlave({}, &msg, &check);
  if (std::optional<Rejection> rejection = check.TakeRejection()) {
    return Error{who + ": " + rejection->message};
  }
  return msg;
}

Expected<rig_extrinsics_t> RigCalibrationToLcm(const RigCalibration& result, int64_t utime,
                                               int64_t t_ns, int8_t distance_unit) {
  rig_extrinsics_t msg;
  msg.version = rig_extrinsics_t::VERSION;
  msg.utime = utime;
  msg.t_ns = t_ns;
  msg.master = result.master;
  msg.distance_unit = distance_unit;
  for (const SlaveCalibration& slave : result.slaves) {
    Expected<slave_extrinsics_t> converted = SlaveCalibrationToLcm(slave);
    if (!converted) return Error{converted.error()};
    msg.slaves.push_back(std::move(converted).value());
  }
  msg.num_slaves = static_cast<int32_t>(msg.slaves.size());
  if (std::optional<Rejection> rejection = CheckMessage(kExtrinsicsChannel, {}, &msg)) {
    return Error{rejection->message};
  }
  return msg;
}

template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                               rig_extrinsics_t*);
template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                      rig_extrinsics_t);
template Expected<rig_extrinsics_t> MessageValidator::Decode(std::string_view, const void*,
                                                             int64_t);

Expected<rig_extrinsics_t> EstimateToLcm(const RigEstimate& estimate, int64_t utime) {
  auto msg = RigCalibrationToLcm(estimate.rig, utime, estimate.t_ns);
  if (!msg) return msg;
  for (size_t i = 0; i < msg->slaves.size() && i < estimate.online.size(); ++i) {
    msg->slaves[i].flags |= WireFlagsOfFacts(estimate.online[i].flags);
    // Cameras that run free: an offset still being (re)estimated, and the jumps of it.
    const SlaveOnlineState& state = estimate.online[i];
    slave_extrinsics_t& slave = msg->slaves[i];
    slave.clock_jumps = state.clock_jumps;
    if (state.clock_offset_estimated && !state.clock_offset_known) {
      slave.time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATING;
      slave.time_offset_s = 0.0;
      slave.time_offset_std_s = -1.0;
    }
  }
  return msg;
}

}  // namespace rigcal::lcm
