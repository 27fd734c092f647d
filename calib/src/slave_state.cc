// SPDX-License-Identifier: Apache-2.0
#include "rigcal/calib/slave_state.h"

#include <algorithm>

namespace rigcal {

std::string_view ToString(SlaveState state) {
  switch (state) {
    case SlaveState::kInitialising:
      return "initialising";
    case SlaveState::kUsable:
      return "usable";
    case SlaveState::kConverged:
      return "converged";
    case SlaveState::kDecalibrated:
      return "decalibrated";
  }
  return "unknown";
}

std::string_view ToString(RigState state) {
  switch (state) {
    case RigState::kIdle:
      return "idle";
    case RigState::kInitialising:
      return "initialising";
    case RigState::kDegraded:
      return "degraded";
    case RigState::kUsable:
      return "usable";
    case RigState::kConverged:
      return "converged";
    case RigState::kDecalibrated:
      return "decalibrated";
  }
  return "unknown";
}

std::vector<std::string_view> FactNames(uint32_t facts) {
  std::vector<std::string_view> names;
  if (facts & kFlagTranslationalOnly) names.push_back("translational-only");
  if (facts & kFlagPlanar) names.push_back("planar");
  if (facts & kFlagRefined) names.push_back("refined");
  return names;
}

std::string StateText(SlaveState state, uint32_t facts) {
  std::string text(ToString(state));
  for (std::string_view fact : FactNames(facts)) (text += ' ') += fact;
  return text;
}

RigState CombineStates(const std::vector<SlaveState>& slaves, bool any_motion) {
  const auto count = [&](auto pred) { return std::count_if(slaves.begin(), slaves.end(), pred); };
  if (count([](SlaveState s) { return s == SlaveState::kDecalibrated; }) > 0)
    return RigState::kDecalibrated;
  const auto usable = count([](SlaveState s) { return IsUsable(s); });
  const auto converged = count([](SlaveState s) { return s == SlaveState::kConverged; });
  const auto n = static_cast<std::ptrdiff_t>(slaves.size());
  if (n > 0 && converged == n) return RigState::kConverged;
  if (n > 0 && usable == n) return RigState::kUsable;
  if (usable > 0) return RigState::kDegraded;
  return any_motion ? RigState::kInitialising : RigState::kIdle;
}

int ExitCodeFor(const std::vector<SlaveState>& slaves) {
  const bool all_usable = !slaves.empty() && std::all_of(slaves.begin(), slaves.end(),
                                                         [](SlaveState s) { return IsUsable(s); });
  return all_usable ? 0 : 3;
}

}  // namespace rigcal
