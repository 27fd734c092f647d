// SPDX-License-Identifier: Apache-2.0
// CheckGivenTimeOffsets: what the data say about timing when no offset is estimated
// (time_offset.h).
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/format.h"
#include "rigcal/io/time_offset.h"

namespace rigcal::io {
namespace {

// How far beyond the given offset the data's preference must lie, in its σ. (The preferred
// offset is measured with both cameras interpolated at instants spread evenly over a frame, so
// it is no longer drawn towards the middle between frames: no floor in frame intervals.)
constexpr double kTimingSigmas = 3.0;

// The offset the data prefer around `given_s`, with the rotation `master_from_slave`.
std::optional<TimeOffsetEstimate> PreferredOffset(const TimedTrajectory& master,
                                                  const TimedTrajectory& slave, double given_s,
                                                  const Eigen::Quaterniond& master_from_slave,
                                                  TimeOffsetOptions options) {
  options.center_s = given_s;
  const Expected<TimeOffsetEstimate> correlated = CorrelateAngularSpeed(master, slave, options);
  if (!correlated) return std::nullopt;
  const TimeOffsetEstimate refined =
      RefineTimeOffset(master, slave, master_from_slave, *correlated, options);
  if (!std::isfinite(refined.std_s) || !(refined.std_s > 0.0)) return std::nullopt;
  return refined;
}

}  // namespace

std::vector<std::string> CheckGivenTimeOffsets(const TimedTrajectory& master,
                                               const std::vector<TimedTrajectory>& slaves,
                                               const std::vector<std::optional<double>>& given_s,
                                               const TimeOffsetOptions& offset_options,
                                               RigCalibration* result) {
  std::vector<std::string> found;
  for (size_t i = 0; i < result->slaves.size() && i < slaves.size() && i < given_s.size(); ++i) {
    SlaveCalibration& s = result->slaves[i];
    if (!given_s[i] || !s.usable() || s.name != slaves[i].name) continue;
    const std::optional<TimeOffsetEstimate> preferred =
        PreferredOffset(master, slaves[i], *given_s[i], s.estimate.q, offset_options);
    if (!preferred) continue;
    const double z = (preferred->offset_s - *given_s[i]) / preferred->std_s;
    if (std::abs(z) <= kTimingSigmas) continue;
    const std::string text =
        "timing: the data prefer a time offset of " + FixedText(preferred->offset_s * 1e3, 2) +
        " ms (σ " + SignificantText(preferred->std_s * 1e3, 2) + " ms) for '" + s.name + "', " +
        SignificantText(std::abs(z), 3) + "σ from the " + FixedText(*given_s[i] * 1e3, 2) +
        " ms it was matched at: its stamps are off (a frame late, a clock shifted); solve "
        "again with --time-offset auto";
    s.contradiction = s.contradiction.empty() ? text : s.contradiction + "; " + text;
    s.state = SlaveState::kInitialising;
    s.message = "not usable: " + text + "; " + s.message;
    found.push_back(text);
  }
  return found;
}

}  // namespace rigcal::io
