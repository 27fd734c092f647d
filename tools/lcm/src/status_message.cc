// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/status_message.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>
#include <utility>

#include "message_checker.h"
#include "message_codec.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/slave_extrinsics_t.hpp"

namespace rigcal::lcm {
namespace {

using internal::Checker;
using internal::LayoutWalk;

// The rules of one camera_status_t (status_message.h).
void CheckCameraStatus(const CameraNames& names, camera_status_t* c, Checker* check) {
  check->CameraName("name", c->name, names, 0, "the rig's cameras");
  check->Finite("fps", c->fps);
  check->AtLeast("fps", c->fps, 0.0);
  const std::pair<const char*, int64_t> counters[] = {
      {"frames_received", c->frames_received},
      {"dropped_late", c->dropped_late},
      {"dropped_duplicate", c->dropped_duplicate},
      {"dropped_out_of_order", c->dropped_out_of_order},
      {"dropped_overflow", c->dropped_overflow},
      {"dropped_never_matched", c->dropped_never_matched},
      {"dropped_invalid", c->dropped_invalid}};
  for (const auto& [field, value] : counters) check->AtLeast<int64_t>(field, value, 0);
  check->InRange<int8_t>("vo_state", c->vo_state, camera_status_t::VO_INITIALISING,
                         camera_status_t::VO_DEAD);
  check->AtLeast<int64_t>("last_pose_age_ms", c->last_pose_age_ms, -1);
  check->AtLeast<int32_t>("vo_segment", c->vo_segment, -1);
  check->AtLeast<int32_t>("relocalisations", c->relocalisations, 0);
  check->InRange<int8_t>("time_offset_source", c->time_offset_source,
                         slave_extrinsics_t::TIME_OFFSET_NONE,
                         slave_extrinsics_t::TIME_OFFSET_ESTIMATED);
  for (const auto& [field, value] :
       {std::pair<const char*, double>{"time_offset_s", c->time_offset_s},
        {"time_offset_std_s", c->time_offset_std_s},
        {"clock_drift_ppm", c->clock_drift_ppm},
        {"clock_drift_std_ppm", c->clock_drift_std_ppm}}) {
    check->Finite(field, value);
  }
  check->AtLeast("time_offset_std_s", c->time_offset_std_s, -1.0);
  check->AtLeast("clock_drift_std_ppm", c->clock_drift_std_ppm, -1.0);
  check->AtLeast<int32_t>("clock_jumps", c->clock_jumps, 0);
}

// σ on LCM: -1 when unknown (NaN).
double LcmSigma(double sigma) { return std::isfinite(sigma) && sigma >= 0.0 ? sigma : -1.0; }

// The clock fields of camera `camera` (0: the master, the reference) from the estimate.
void FillClock(const RigEstimate& estimate, size_t camera, camera_status_t* c) {
  c->time_offset_source = slave_extrinsics_t::TIME_OFFSET_NONE;
  c->time_offset_std_s = -1.0;
  c->clock_drift_std_ppm = -1.0;
  // The master: restarts of its clock followed (cameras that run free).
  if (camera == 0) c->clock_jumps = estimate.master_clock_jumps;
  if (camera == 0 || camera > estimate.rig.slaves.size()) return;
  const SlaveCalibration& s = estimate.rig.slaves[camera - 1];
  const SlaveOnlineState* online =
      camera <= estimate.online.size() ? &estimate.online[camera - 1] : nullptr;
  if (online != nullptr) c->clock_jumps = online->clock_jumps;
  if (online != nullptr && online->clock_offset_estimated) {
    if (!online->clock_offset_known) {
      c->time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATING;
      return;
    }
    c->time_offset_source = slave_extrinsics_t::TIME_OFFSET_ESTIMATED;
    c->time_offset_s = std::isfinite(s.time_offset_s) ? s.time_offset_s : 0.0;
    c->time_offset_std_s = LcmSigma(s.time_offset_std_s);
    c->clock_drift_ppm = std::isfinite(online->clock_drift_ppm) ? online->clock_drift_ppm : 0.0;
    c->clock_drift_std_ppm = LcmSigma(online->clock_drift_std_ppm);
  } else if (std::isfinite(s.time_offset_s)) {
    c->time_offset_source = slave_extrinsics_t::TIME_OFFSET_GIVEN;
    c->time_offset_s = s.time_offset_s;
  }
}

// The fields of rig_status_t.lcm up to num_cameras.
void WalkStatusLayout(LayoutWalk* walk) {
  walk->Fixed("version", 2);
  walk->Fixed("utime", 8);
  const int32_t cameras = walk->Count("num_cameras", camera_status_t()._getEncodedSizeNoHash());
  // camera_status_t: name, then fixed-size fields (an empty string takes 4 + 1 bytes).
  const int64_t fixed = camera_status_t()._getEncodedSizeNoHash() - 5;
  for (int32_t i = 0; i < cameras; ++i) {
    const std::string camera = "cameras[" + std::to_string(i) + "]";
    walk->String(camera + ".name");
    walk->Fixed(camera, fixed);
  }
  walk->Fixed("sync_sets_emitted", 8);
  walk->Fixed("sync_fill", 4);
  walk->Fixed("sync_capacity", 4);
  walk->Fixed("estimator_state", 1);
  walk->String("estimator_message");
}

// The rules of rig_status_t (status_message.h) but the version.
void CheckStatus(const CameraNames& names, rig_status_t* msg, Checker* check) {
  check->Count("num_cameras", msg->num_cameras, msg->cameras.size(), "cameras");
  if (!check->ok()) return;
  check->Finite("cpu_percent", msg->cpu_percent);
  check->AtLeast<int64_t>("utime", msg->utime, 0);
  check->AtLeast<int64_t>("sync_sets_emitted", msg->sync_sets_emitted, 0);
  check->AtLeast<int32_t>("sync_capacity", msg->sync_capacity, 0);
  check->InRange<int32_t>("sync_fill", msg->sync_fill, 0, msg->sync_capacity);
  check->InRange<int8_t>("estimator_state", msg->estimator_state, rig_status_t::ESTIMATOR_IDLE,
                         rig_status_t::ESTIMATOR_DECALIBRATED);
  check->AtLeast("cpu_percent", msg->cpu_percent, 0.0);
  check->AtLeast<int64_t>("rss_bytes", msg->rss_bytes, 0);
  check->Text("estimator_message", msg->estimator_message);
  check->NamedElements("cameras", &msg->cameras, {}, [&](camera_status_t* c, Checker* nested) {
    CheckCameraStatus(names, c, nested);
  });
}

}  // namespace

template <>
struct internal::MessageTraits<rig_status_t> {
  static constexpr char kTypeName[] = "rig_status_t";
  static constexpr auto WalkLayout = &WalkStatusLayout;
  static constexpr auto CheckContent = &CheckStatus;
};

double StampRate::Update(int64_t count_now, int64_t newest_t_ns, int64_t start_ns) {
  const int64_t since = t_ns >= 0 ? t_ns : start_ns;
  double rate = 0.0;
  if (since >= 0 && newest_t_ns > since) {
    rate =
        static_cast<double>(count_now - count) / (static_cast<double>(newest_t_ns - since) * 1e-9);
  }
  count = count_now;
  if (newest_t_ns >= 0) t_ns = newest_t_ns;
  return std::max(0.0, rate);
}

rig_status_t MakeRigStatus(const std::vector<CameraStatusInput>& cameras, const SyncStats& sync,
                           int32_t sync_capacity, const RigEstimate& estimate, double cpu_percent,
                           int64_t utime) {
  rig_status_t msg{};
  msg.version = rig_status_t::VERSION;
  msg.utime = utime;
  msg.num_cameras = static_cast<int32_t>(cameras.size());
  for (size_t i = 0; i < cameras.size(); ++i) {
    const CameraStatusInput& input = cameras[i];
    camera_status_t cam{};
    cam.name = input.name;
    cam.fps = input.fps;
    cam.frames_received = input.frames_received;
    cam.dropped_invalid = input.dropped_invalid;
    cam.dropped_overflow = input.dropped_backlog;
    if (i < sync.cameras.size()) {
      const SyncCameraStats& s = sync.cameras[i];
      // A pose consumed before a restart (resume) is as late as it gets.
      cam.dropped_late = static_cast<int64_t>(s.late + s.consumed);
      cam.dropped_duplicate = static_cast<int64_t>(s.duplicate);
      cam.dropped_out_of_order = static_cast<int64_t>(s.out_of_order);
      // Ring overflow, and this camera's members of sets the full ready queue dropped.
      cam.dropped_overflow += static_cast<int64_t>(s.overflow + s.consumer_overflow);
      cam.dropped_never_matched = static_cast<int64_t>(s.never_matched);
      // A clock glitch is a pose with an implausible stamp: reported as invalid.
      cam.dropped_invalid += static_cast<int64_t>(s.invalid + s.clock_glitch);
    }
    cam.vo_state = input.vo_state;
    cam.last_pose_age_ms = input.last_pose_age_ms;
    cam.vo_segment = input.vo_segment;
    cam.relocalisations = input.relocalisations;
    FillClock(estimate, i, &cam);
    msg.cameras.push_back(cam);
  }
  msg.sync_sets_emitted = static_cast<int64_t>(sync.sets_emitted);
  const SyncCameraStats& total = sync.total;
  const int64_t dropped = static_cast<int64_t>(total.Dropped());
  const int64_t fill =
      static_cast<int64_t>(total.pushed) - static_cast<int64_t>(total.used) - dropped;
  msg.sync_capacity = std::max<int32_t>(0, sync_capacity);
  msg.sync_fill = static_cast<int32_t>(std::clamp<int64_t>(fill, 0, msg.sync_capacity));
  msg.estimator_state = EstimatorState(estimate, &msg.estimator_message);
  msg.cpu_percent = std::max(0.0, cpu_percent);
  msg.rss_bytes = ResidentSetBytes();
  return msg;
}

int8_t EstimatorState(const RigEstimate& estimate, std::string* message) {
  std::vector<SlaveState> states;
  std::string decalibrated, not_usable;
  int converged = 0;
  int usable = 0;
  for (const SlaveCalibration& slave : estimate.rig.slaves) {
    states.push_back(slave.state);
    if (slave.state == SlaveState::kConverged) ++converged;
    if (slave.usable()) ++usable;
    std::string& list = slave.state == SlaveState::kDecalibrated ? decalibrated : not_usable;
    if (!slave.usable()) list += (list.empty() ? "" : ", ") + slave.name;
  }
  const RigState state = CombineStates(states, estimate.sets > 0);
  const size_t slaves = states.size();
  std::ostringstream text;
  switch (state) {
    case RigState::kIdle:
      text << "no synchronised pose sets yet";
      break;
    case RigState::kInitialising:
      text << "collecting motion (" << estimate.sets << " sets)";
      break;
    case RigState::kDegraded:
      text << usable << " of " << slaves << " slaves usable; not yet: " << not_usable;
      break;
    case RigState::kUsable:
      text << "all " << slaves << " slaves usable, " << converged << " converged";
      break;
    case RigState::kConverged:
      text << "all " << slaves << " slaves converged";
      break;
    case RigState::kDecalibrated:
      text << "decalibrated: " << decalibrated << " moved; re-estimating";
      break;
  }
  if (message != nullptr) *message = text.str();
  return static_cast<int8_t>(state);
}

template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&, rig_status_t*);
template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                      rig_status_t);
template Expected<rig_status_t> MessageValidator::Decode(std::string_view, const void*, int64_t);

}  // namespace rigcal::lcm
