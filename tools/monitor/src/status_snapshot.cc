// SPDX-License-Identifier: Apache-2.0
#include "rigcal/monitor/status_snapshot.h"

#include <cmath>
#include <sstream>
#include <vector>

#include "rigcal/calib/slave_state.h"
#include "rigcal/io/result_json.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/slave_view.h"

namespace rigcal::monitor {
namespace {

// -1 (unknown on LCM) and non-finite values as null.
nlohmann::json Sigma(double v) {
  return v >= 0.0 && std::isfinite(v) ? nlohmann::json(v) : nullptr;
}

nlohmann::json Vec3(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

const char* TimeOffsetSourceName(int8_t source);

nlohmann::json CameraJson(const camera_status_t& c) {
  return {
      {"name", c.name},
      {"fps", c.fps},
      {"frames_received", c.frames_received},
      {"dropped",
       {{"late", c.dropped_late},
        {"duplicate", c.dropped_duplicate},
        {"out_of_order", c.dropped_out_of_order},
        {"overflow", c.dropped_overflow},
        {"never_matched", c.dropped_never_matched},
        {"invalid", c.dropped_invalid}}},
      {"vo_state", VoStateName(c.vo_state)},
      {"vo_segment", c.vo_segment >= 0 ? nlohmann::json(c.vo_segment) : nullptr},
      {"relocalisations", c.relocalisations},
      {"last_pose_age_ms", c.last_pose_age_ms >= 0 ? nlohmann::json(c.last_pose_age_ms) : nullptr},
      {"clock",
       {{"source", TimeOffsetSourceName(c.time_offset_source)},
        {"offset_s", c.time_offset_s},
        {"std_s", Sigma(c.time_offset_std_s)},
        {"drift_ppm", c.clock_drift_ppm},
        {"drift_std_ppm", Sigma(c.clock_drift_std_ppm)},
        {"jumps", c.clock_jumps}}}};
}

const char* TimeOffsetSourceName(int8_t source) {
  switch (source) {
    case slave_extrinsics_t::TIME_OFFSET_NONE:
      return "none";
    case slave_extrinsics_t::TIME_OFFSET_GIVEN:
      return "given";
    case slave_extrinsics_t::TIME_OFFSET_ESTIMATING:
      return "estimating";
    case slave_extrinsics_t::TIME_OFFSET_ESTIMATED:
      return "estimated";
  }
  return "?";
}

nlohmann::json SlaveJson(const slave_extrinsics_t& s) {
  const lcm::SlaveView view = lcm::ViewOf(s);
  const io::AxisAngleDegrees a = io::AxisAngleDeg(view.q);
  nlohmann::json facts = nlohmann::json::array();
  for (const std::string& fact : view.facts) facts.push_back(fact);
  return {{"name", s.name},
          {"state", SlaveStateName(s.state)},
          {"q_wxyz", {s.q[0], s.q[1], s.q[2], s.q[3]}},
          {"roll_pitch_yaw_deg", Vec3(io::RollPitchYawDeg(view.q))},
          {"axis_angle", {{"axis", Vec3(a.axis)}, {"angle_deg", a.angle_deg}}},
          {"C", {s.C[0], s.C[1], s.C[2]}},
          {"scale", s.scale},
          {"segment", s.segment},
          {"std",
           {{"rot_deg", Sigma(s.rot_std_deg)},
            {"pos", {Sigma(s.pos_std[0]), Sigma(s.pos_std[1]), Sigma(s.pos_std[2])}},
            {"scale", Sigma(s.scale_std)},
            {"axis", Sigma(s.axis_offset_std)}}},
          {"motions_used", s.motions_used},
          {"motions_rejected", s.motions_rejected},
          {"facts", facts},
          {"time_offset",
           {{"source", TimeOffsetSourceName(s.time_offset_source)},
            {"offset_s", s.time_offset_s},
            {"std_s", Sigma(s.time_offset_std_s)},
            {"jumps", s.clock_jumps}}},
          {"message", s.message}};
}

}  // namespace

Health HealthOf(const MonitorSnapshot& snapshot) {
  RigState state;
  if (snapshot.status) {
    state = static_cast<RigState>(snapshot.status->estimator_state);
  } else if (snapshot.extrinsics) {
    std::vector<SlaveState> slaves;
    for (const slave_extrinsics_t& s : snapshot.extrinsics->slaves) {
      slaves.push_back(lcm::ViewOf(s).state);
    }
    state = CombineStates(slaves, true);
  } else {
    return Health::kNoData;
  }
  if (state == RigState::kConverged) return Health::kConverged;
  if (state == RigState::kDecalibrated) return Health::kDecalibrated;
  return Health::kConverging;
}

const char* ToString(Health health) {
  switch (health) {
    case Health::kConverged:
      return "converged";
    case Health::kConverging:
      return "converging";
    case Health::kDecalibrated:
      return "decalibrated";
    case Health::kNoData:
      return "no_data";
  }
  return "?";
}

const char* VoStateName(int8_t vo_state) {
  switch (vo_state) {
    case camera_status_t::VO_INITIALISING:
      return "initialising";
    case camera_status_t::VO_TRACKING:
      return "tracking";
    case camera_status_t::VO_LOST:
      return "lost";
    case camera_status_t::VO_DEAD:
      return "dead";
    default:
      return "?";
  }
}

std::string EstimatorStateName(int8_t estimator_state) {
  if (estimator_state < rig_status_t::ESTIMATOR_IDLE ||
      estimator_state > rig_status_t::ESTIMATOR_DECALIBRATED) {
    return "?";
  }
  return std::string(ToString(static_cast<RigState>(estimator_state)));
}

std::string SlaveStateName(int8_t state) {
  if (state < slave_extrinsics_t::STATE_INITIALISING ||
      state > slave_extrinsics_t::STATE_DECALIBRATED) {
    return "?";
  }
  return std::string(ToString(static_cast<SlaveState>(state)));
}

nlohmann::json SnapshotToJson(const MonitorSnapshot& snapshot) {
  const Health health = HealthOf(snapshot);
  nlohmann::json out = {{"source", snapshot.source},
                        {"health", ToString(health)},
                        {"exit_code", static_cast<int>(health)},
                        {"listening_s", snapshot.listening_s},
                        {"status", nullptr},
                        {"extrinsics", nullptr},
                        {"rejected_messages", snapshot.decode.TotalRejected()}};
  if (const auto& st = snapshot.status) {
    nlohmann::json cameras = nlohmann::json::array();
    for (const camera_status_t& c : st->cameras) cameras.push_back(CameraJson(c));
    out["status"] = {{"age_s", snapshot.status_age_s},
                     {"estimator_state", EstimatorStateName(st->estimator_state)},
                     {"estimator_message", st->estimator_message},
                     {"cameras", cameras},
                     {"sync",
                      {{"sets_emitted", st->sync_sets_emitted},
                       {"fill", st->sync_fill},
                       {"capacity", st->sync_capacity}}},
                     {"process", {{"cpu_percent", st->cpu_percent}, {"rss_bytes", st->rss_bytes}}}};
  }
  if (const auto& ex = snapshot.extrinsics) {
    nlohmann::json slaves = nlohmann::json::array();
    for (const slave_extrinsics_t& s : ex->slaves) slaves.push_back(SlaveJson(s));
    out["extrinsics"] = {
        {"age_s", snapshot.extrinsics_age_s},
        {"t_ns", ex->t_ns},
        {"master", ex->master},
        {"distance_unit",
         ex->distance_unit == rig_extrinsics_t::UNIT_METRE ? "metre" : "master_odometry"},
        {"slaves", slaves}};
  }
  return out;
}

}  // namespace rigcal::monitor
