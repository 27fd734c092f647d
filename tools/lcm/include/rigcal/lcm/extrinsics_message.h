// SPDX-License-Identifier: Apache-2.0
#pragma once
// rig_extrinsics_t, the rig calibration on RIGCAL_EXTRINSICS: its checks, the flags of
// slave_extrinsics_t, and its conversion from a RigCalibration.

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/rig_estimator.h"
#include "rigcal/base/status.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/rig_extrinsics_t.hpp"

namespace rigcal::lcm {

// slave_extrinsics_t::FLAG_* as int32_t: lcm-gen emits every constant as its own anonymous enum,
// and C++20 deprecates `|` between different enums. Combine these instead. The flags are facts
// about what the motions determine; the state is slave_extrinsics_t::state. The bits differ from
// the estimator's SlaveFlags (slave_state.h), hence their own names; WireFlagsOfFacts and
// FactsOfWireFlags are the one mapping between them.
inline constexpr int32_t kWireFlagTranslationalOnly = slave_extrinsics_t::FLAG_TRANSLATIONAL_ONLY;
inline constexpr int32_t kWireFlagPlanar = slave_extrinsics_t::FLAG_PLANAR_UNOBSERVABLE_AXIS;
inline constexpr int32_t kWireFlagAxisFromPrior = slave_extrinsics_t::FLAG_AXIS_FROM_PRIOR;
inline constexpr int32_t kWireFlagRefined = slave_extrinsics_t::FLAG_REFINED;
inline constexpr int32_t kKnownFlags =
    kWireFlagTranslationalOnly | kWireFlagPlanar | kWireFlagAxisFromPrior | kWireFlagRefined;

// slave_extrinsics_t::STATE_* is rigcal::SlaveState (slave_state.h), number for number.
static_assert(slave_extrinsics_t::STATE_INITIALISING ==
              static_cast<int>(SlaveState::kInitialising));
static_assert(slave_extrinsics_t::STATE_USABLE == static_cast<int>(SlaveState::kUsable));
static_assert(slave_extrinsics_t::STATE_CONVERGED == static_cast<int>(SlaveState::kConverged));
static_assert(slave_extrinsics_t::STATE_DECALIBRATED ==
              static_cast<int>(SlaveState::kDecalibrated));

// The rules of rig_extrinsics_t (beyond message_validation.h), checked by CheckMessage,
// EncodeMessage and MessageValidator::Decode: num_slaves agrees with slaves, the master is
// names[0], utime and t_ns >= 0, a defined distance_unit, and per slave: a slave of the rig named
// once, a message without NUL bytes, finite fields, unit q, a defined state, only defined flags, a
// positive scale when usable or converged, non-negative counters, standard deviations non-negative
// or -1 (unknown), axis_spread_deg in [0, 180], a unit planar_axis with
// FLAG_PLANAR_UNOBSERVABLE_AXIS, FLAG_AXIS_FROM_PRIOR only with it.
extern template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                                      rig_extrinsics_t*);
extern template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                             rig_extrinsics_t);
extern template Expected<rig_extrinsics_t> MessageValidator::Decode(std::string_view, const void*,
                                                                    int64_t);

// Flags of slave_extrinsics_t for a calibration result:
//   TRANSLATIONAL_ONLY       when the motion model is translational (position unobservable);
//   PLANAR_UNOBSERVABLE_AXIS when observability.planar, with AXIS_FROM_PRIOR when C along the
//                            axis is the nominal mounting's.
// REFINED is never set here: only the online estimator knows it (SlaveOnlineState::flags).
int32_t WireFlagsOf(const SlaveCalibration& slave);

// The wire flags of the estimator's facts (SlaveFlags: translational-only, planar, refined), and
// back. FLAG_AXIS_FROM_PRIOR has no estimator fact (it comes from the result, WireFlagsOf).
int32_t WireFlagsOfFacts(uint32_t facts);
uint32_t FactsOfWireFlags(int32_t wire_flags);

// slave_extrinsics_t of one slave. scale/segment/scale_std are those of the current segment
// (the entry of slave.scales with the largest segment id; estimate.scale and segment 0 when
// there is none). rotation_eigen_gap = λ2 - λ1 of observability.rotation_eigenvalues.
// message = ToString(termination) + ": " + slave.message. Clock offset: ESTIMATED when
// time_offset_s and its σ are finite, GIVEN when only time_offset_s is, else NONE (offset 0,
// σ -1); clock_jumps 0 (the online estimator's publisher sets ESTIMATING and the jumps).
// state = slave.state. Placeholders: a slave whose solve produced no estimate gets identity q, zero
// C and scale 1 where its estimate is not finite; non-finite standard deviations become -1
// (unknown: not computed, the covariance failed, or undetermined), never 0; non-finite
// observability figures become 0. Fails when a solved slave's q, C or scale is not finite, when
// observability.planar holds without a finite non-zero axis, or when the result does not pass
// CheckMessage.
Expected<slave_extrinsics_t> SlaveCalibrationToLcm(const SlaveCalibration& slave);

// rig_extrinsics_t of a calibration result published at `utime` (µs). `t_ns`: capture time of
// the newest poses the result includes (0 for a batch result); `distance_unit`: one of
// rig_extrinsics_t::UNIT_*. Fails as SlaveCalibrationToLcm does, naming the slave.
Expected<rig_extrinsics_t> RigCalibrationToLcm(
    const RigCalibration& result, int64_t utime, int64_t t_ns = 0,
    int8_t distance_unit = rig_extrinsics_t::UNIT_MASTER_ODOMETRY);

// The rig_extrinsics_t of an online estimate: the batch conversion plus the estimator's online
// facts (WireFlagsOfFacts) and, for cameras that run free, an offset still being (re)estimated and
// its jumps. Fails as RigCalibrationToLcm does.
Expected<rig_extrinsics_t> EstimateToLcm(const RigEstimate& estimate, int64_t utime);

}  // namespace rigcal::lcm
