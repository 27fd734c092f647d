#pragma once
// Clock offset of a camera that runs free from the data, matched recordings at those offsets.
// The math (angular-speed correlation, refinement) is calib's clock_offset.h.

#include <optional>
#include <vector>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/clock_offset.h"
#include "rigcal/base/status.h"
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
// (CorrelateAngularSpeed, a calibration with `options` at those offsets, RefineTimeOffset for
// every slave whose rotation it solved). Errors: those of CorrelateAngularSpeed and
// MatchFreeRunning.
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

}  // namespace rigcal::io
