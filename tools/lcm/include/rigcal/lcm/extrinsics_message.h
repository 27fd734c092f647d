#pragma once
// rig_extrinsics_t, the rig calibration on RIGCAL_EXTRINSICS: its checks, the flags of
// slave_extrinsics_t, and its conversion from a RigCalibration.

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/status.h"
#include "rigcal/lcm/message_validation.h"
#include "rigcal/rig_extrinsics_t.hpp"

namespace rigcal::tools {

// slave_extrinsics_t::FLAG_* as int32_t: lcm-gen emits every constant as its own anonymous enum,
// and C++20 deprecates `|` between different enums. Combine these instead.
inline constexpr int32_t kFlagInitialising = slave_extrinsics_t::FLAG_INITIALISING;
inline constexpr int32_t kFlagConverged = slave_extrinsics_t::FLAG_CONVERGED;
inline constexpr int32_t kFlagTranslationalOnly = slave_extrinsics_t::FLAG_TRANSLATIONAL_ONLY;
inline constexpr int32_t kFlagPlanar = slave_extrinsics_t::FLAG_PLANAR_UNOBSERVABLE_AXIS;
inline constexpr int32_t kFlagDecalibrated = slave_extrinsics_t::FLAG_DECALIBRATED;
inline constexpr int32_t kFlagAxisFromPrior = slave_extrinsics_t::FLAG_AXIS_FROM_PRIOR;
inline constexpr int32_t kKnownFlags = kFlagInitialising | kFlagConverged | kFlagTranslationalOnly |
                                       kFlagPlanar | kFlagDecalibrated | kFlagAxisFromPrior;

// The rules of rig_extrinsics_t (beyond message_validation.h), checked by CheckMessage,
// EncodeMessage and MessageValidator::Decode: num_slaves agrees with slaves, the master is
// names[0], utime and t_ns >= 0, a defined distance_unit, and per slave: a slave of the rig named
// once, finite fields, unit q, only defined flags with exactly one of INITIALISING and CONVERGED, a
// positive scale when converged, non-negative counters and standard deviations (axis_offset_std may
// be -1, unknown), axis_spread_deg in [0, 180], a unit planar_axis with
// FLAG_PLANAR_UNOBSERVABLE_AXIS, FLAG_AXIS_FROM_PRIOR only with it.
extern template std::optional<Rejection> CheckMessage(std::string_view, const CameraNames&,
                                                      rig_extrinsics_t*);
extern template Expected<std::vector<uint8_t>> EncodeMessage(std::string_view, const CameraNames&,
                                                             rig_extrinsics_t);
extern template Expected<rig_extrinsics_t> MessageValidator::Decode(std::string_view, const void*,
                                                                    int64_t);

// Flags of slave_extrinsics_t for a calibration result:
//   CONVERGED                when slave.usable(), else INITIALISING (no usable estimate yet);
//   TRANSLATIONAL_ONLY       when the motion model is translational (position unobservable);
//   PLANAR_UNOBSERVABLE_AXIS when observability.planar.
// DECALIBRATED is never set here: change detection belongs to the online estimator, which ORs
// kFlagDecalibrated into the message it publishes.
int32_t SlaveFlags(const SlaveCalibration& slave);

// slave_extrinsics_t of one slave. scale/segment/scale_std are those of the current segment
// (the entry of slave.scales with the largest segment id; estimate.scale and segment 0 when
// there is none). rotation_eigen_gap = λ2 - λ1 of observability.rotation_eigenvalues.
// message = ToString(termination) + ": " + slave.message.
// Placeholders: a slave that is not usable gets identity q, zero C and scale 1 where its
// estimate is not finite; non-finite standard deviations and observability figures become 0
// ("not computed"). Fails when a usable slave's q, C or scale is not finite, when
// observability.planar holds without a finite non-zero axis, or when the result does not pass
// CheckMessage.
Expected<slave_extrinsics_t> SlaveCalibrationToLcm(const SlaveCalibration& slave);

// rig_extrinsics_t of a calibration result published at `utime` (µs). `t_ns`: capture time of
// the newest poses the result includes (0 for a batch result); `distance_unit`: one of
// rig_extrinsics_t::UNIT_*. Fails as SlaveCalibrationToLcm does, naming the slave.
Expected<rig_extrinsics_t> RigCalibrationToLcm(
    const RigCalibration& result, int64_t utime, int64_t t_ns = 0,
    int8_t distance_unit = rig_extrinsics_t::UNIT_MASTER_ODOMETRY);

}  // namespace rigcal::tools
