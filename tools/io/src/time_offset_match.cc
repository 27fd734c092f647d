// MatchWithTimeOffsets: given or estimated clock offsets, then the matched recording.
#include <cmath>
#include <string>

#include "rigcal/base/logging.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/io/time_offset.h"
#include "rigcal/io/trajectory_interpolation.h"

namespace rigcal::io {
namespace {

std::vector<int64_t> OffsetsNs(const std::vector<TimeOffsetEstimate>& offsets) {
  std::vector<int64_t> ns;
  for (const TimeOffsetEstimate& o : offsets) ns.push_back(std::llround(o.offset_s * 1e9));
  return ns;
}

}  // namespace

Expected<OffsetMatch> MatchWithTimeOffsets(const TimedTrajectory& master,
                                           const std::vector<TimedTrajectory>& slaves,
                                           std::optional<double> given_offset_s,
                                           int64_t tolerance_ns, const CalibrationOptions& options,
                                           const TimeOffsetOptions& offset_options) {
  return MatchWithTimeOffsets(master, slaves,
                              std::vector<std::optional<double>>(slaves.size(), given_offset_s),
                              tolerance_ns, options, offset_options);
}

Expected<OffsetMatch> MatchWithTimeOffsets(
    const TimedTrajectory& master, const std::vector<TimedTrajectory>& slaves,
    const std::vector<std::optional<double>>& given_offsets_s, int64_t tolerance_ns,
    const CalibrationOptions& options, const TimeOffsetOptions& offset_options) {
  const auto log = ModuleLogger("tools");
  if (given_offsets_s.size() != slaves.size()) {
    return Error{"one time offset (or auto) per slave expected, got " +
                 std::to_string(given_offsets_s.size()) + " for " + std::to_string(slaves.size()) +
                 " slaves"};
  }
  OffsetMatch out;
  bool any_estimated = false;
  for (size_t i = 0; i < slaves.size(); ++i) {
    const TimedTrajectory& slave = slaves[i];
    if (given_offsets_s[i]) {
      TimeOffsetEstimate given;
      given.offset_s = *given_offsets_s[i];
      out.offsets.push_back(given);
      continue;
    }
    any_estimated = true;
    auto correlated = CorrelateAngularSpeed(master, slave, offset_options);
    if (!correlated) return Error{correlated.error()};
    log->info("time offset of '{}': angular-speed correlation {:.3f} at {:.6f} s", slave.name,
              correlated->correlation, correlated->offset_s);
    out.offsets.push_back(*correlated);
  }
  auto matched =
      MatchFreeRunning(master, slaves, OffsetsNs(out.offsets), tolerance_ns, {}, &out.interpolated);
  if (!matched) return Error{matched.error()};
  if (any_estimated) {
    const RigCalibration first = CalibrateRig(*matched, options);
    for (size_t i = 0; i < slaves.size() && i < first.slaves.size(); ++i) {
      if (given_offsets_s[i] || !first.slaves[i].solved() || first.slaves[i].name != slaves[i].name)
        continue;
      out.offsets[i] = RefineTimeOffset(master, slaves[i], first.slaves[i].estimate.q,
                                        out.offsets[i], offset_options);
      log->info("time offset of '{}': {:.6f} s (std {:.3g} s, {} motions)", slaves[i].name,
                out.offsets[i].offset_s, out.offsets[i].std_s, out.offsets[i].motions);
    }
    matched = MatchFreeRunning(master, slaves, OffsetsNs(out.offsets), tolerance_ns, {},
                               &out.interpolated);
    if (!matched) return Error{matched.error()};
  }
  out.recording = std::move(*matched);
  return out;
}

}  // namespace rigcal::io
