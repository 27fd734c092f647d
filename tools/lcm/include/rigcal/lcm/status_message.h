// SPDX-License-Identifier: Apache-2.0
#pragma once
// rig_status_t, the health of a running calibration on RIGCAL_STATUS: its checks, and the
// message built from the estimator, shared by `rigcal calib` (poses from the bus) and `rigcal run`
// (the live pipeline).

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/calib/rig_estimator.h"
#include "rigcal/base/status.h"
#include "rigcal/calib/sync_buffer.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/rig_status_t.hpp"

namespace rigcal::lcm {

// The rules of rig_status_t (beyond message_validation.h), checked by CheckMessage, EncodeMessage
// and MessageValidator::Decode: num_cameras agrees with cameras, finite cpu_percent >= 0, utime,
// sync_sets_emitted, sync_capacity and rss_bytes >= 0, sync_fill in [0, sync_capacity], a defined
// estimator_state, an estimator_message without NUL bytes, and per camera: a camera of the rig
// named once, finite fps >= 0, counters >= 0, a defined vo_state, last_pose_age_ms >= -1,
// vo_segment >= -1, a defined time_offset_source, finite clock values, σ >= -1, clock_jumps >= 0.
extern template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                                      rig_status_t*);
extern template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                             rig_status_t);
extern template Expected<rig_status_t> MessageValidator::Decode(std::string_view, const void*,
                                                                int64_t);

// What the caller knows of one camera beyond the sync buffer's counters.
struct CameraStatusInput {
  std::string name;
  double fps = 0.0;             // over the last status period, from stamps (StampRate)
  int64_t frames_received = 0;  // cumulative
  int64_t dropped_invalid = 0;  // rejected before the sync buffer (decoder, ...)
  int64_t dropped_backlog = 0;  // dropped before the sync buffer because a stage fell behind
  int8_t vo_state = camera_status_t::VO_INITIALISING;
  int64_t last_pose_age_ms = -1;  // -1 when no pose yet
  int32_t vo_segment = -1;        // scale segment of the newest pose, -1 when no pose yet
  int32_t relocalisations = 0;    // cumulative: tracking regained in the same segment
};

// camera_status_t.fps: frames (or poses) per second of one camera from their STAMPS between two
// status messages, so a replay or a run faster than real time reports the camera's rate, not
// the wall clock's.
struct StampRate {
  int64_t count = 0;  // at the previous status
  int64_t t_ns = -1;  // newest stamp at the previous status

  // The rate of `count_now - count` items up to stamp `newest_t_ns`; `start_ns` stands for the
  // previous stamp at the first status (-1: none, rate 0). Remembers this status.
  double Update(int64_t count_now, int64_t newest_t_ns, int64_t start_ns);
};

// rig_status_t from the caller's per-camera view, the sync buffer's counters (drops by cause,
// fill), the estimate (estimator state and message; per slave its clock offset, drift, σ and
// jumps when the cameras run free) and the process's CPU and RSS.
rig_status_t MakeRigStatus(const std::vector<CameraStatusInput>& cameras, const SyncStats& sync,
                           int32_t sync_capacity, const RigEstimate& estimate, double cpu_percent,
                           int64_t utime);

// rig_status_t estimator_state of an estimate: the RigState (slave_state.h) combined from the
// slaves' states (IDLE before the first set), and a one-line message naming the slaves that
// hold it back.
static_assert(rig_status_t::ESTIMATOR_IDLE == static_cast<int>(RigState::kIdle));
static_assert(rig_status_t::ESTIMATOR_INITIALISING == static_cast<int>(RigState::kInitialising));
static_assert(rig_status_t::ESTIMATOR_DEGRADED == static_cast<int>(RigState::kDegraded));
static_assert(rig_status_t::ESTIMATOR_USABLE == static_cast<int>(RigState::kUsable));
static_assert(rig_status_t::ESTIMATOR_CONVERGED == static_cast<int>(RigState::kConverged));
static_assert(rig_status_t::ESTIMATOR_DECALIBRATED == static_cast<int>(RigState::kDecalibrated));
int8_t EstimatorState(const RigEstimate& estimate, std::string* message);

}  // namespace rigcal::lcm
