// SPDX-License-Identifier: Apache-2.0
#pragma once
// Clock offset of a camera that runs free from the data, matched recordings at those offsets.
// The math (angular-speed correlation, refinement) is calib's clock_offset.h.

#include <optional>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/calibration_result.h"
#include "rigcal/calib/clock_offset.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::io {

// The recording of a rig whose cameras may run free, matched at the slaves' time offsets
// (MatchFreeRunning), and those offsets.
struct OffsetMatch {
  RigRecording recording;
  std::vector<TimeOffsetEstimate> offsets;  // per slave
  std::vector<bool> interpolated;           // per slave: interpolated, not matched by stamp
};

// `given_offset_s`: every slave's offset (σ unknown); nullopt: estimated per slave
// (CorrelateAngularSpeed, then calibration with `options` at the offsets and RefineTimeOffset
// for every slave whose rotation it solved, alternated until no offset moves by a tenth of its
// σ: a single step leaves the offset biased towards the correlation's, as the rotation of the
// calibration at the correlation's offset absorbs part of its error). Errors: those of
// CorrelateAngularSpeed and MatchFreeRunning.
Expected<OffsetMatch> MatchWithTimeOffsets(const TimedTrajectory& master,
                                           const std::vector<TimedTrajectory>& slaves,
                                           std::optional<double> given_offset_s,
                                           int64_t tolerance_ns, const CalibrationOptions& options,
                                           const TimeOffsetOptions& offset_options = {});

// Per slave: `given_offsets_s[i]` the offset of slave i (σ unknown), nullopt = estimated as
// above. One entry per slave (an error otherwise).
Expected<OffsetMatch> MatchWithTimeOffsets(
    const TimedTrajectory& master, const std::vector<TimedTrajectory>& slaves,
    const std::vector<std::optional<double>>& given_offsets_s, int64_t tolerance_ns,
    const CalibrationOptions& options, const TimeOffsetOptions& offset_options = {});

// The estimated offsets' uncertainty in `result` (the calibration of match.recording): every
// estimated slave's σ of rotation, C and scales grows by the change of its solution over ±σ of
// its offset (the sensitivity of the solution to the offset, half the difference of the
// calibrations at τ + σ_τ and τ - σ_τ, added in quadrature). Slaves with a given offset or an
// unknown σ_τ are left as they are. Errors: those of MatchFreeRunning.
Status PropagateTimeOffsetSigma(const TimedTrajectory& master,
                                const std::vector<TimedTrajectory>& slaves,
                                const OffsetMatch& match, int64_t tolerance_ns,
                                const CalibrationOptions& options, RigCalibration* result);

// Timing checked when the offsets are given (0: synchronised cameras): per slave whose offset
// is given and whose estimate in `result` is usable, the offset the data prefer
// (CorrelateAngularSpeed within ±offset_options.search_window_s of the given offset,
// RefineTimeOffset with the solved rotation), nullopt when it cannot be measured. When it lies
// beyond 3σ from the given offset the slave's stamps are off (a frame late, a shifted clock):
// the slave's state becomes initialising, its `contradiction` and message say so and suggest
// --time-offset auto, and the text is returned for the log. One entry per slave of `result`.
std::vector<std::string> CheckGivenTimeOffsets(const TimedTrajectory& master,
                                               const std::vector<TimedTrajectory>& slaves,
                                               const std::vector<std::optional<double>>& given_s,
                                               const TimeOffsetOptions& offset_options,
                                               RigCalibration* result);

}  // namespace rigcal::io
