// SPDX-License-Identifier: Apache-2.0
#pragma once
// One meaning per state. Every surface that says how far a slave's calibration has got — the
// batch result, the online estimate, RIGCAL_EXTRINSICS / RIGCAL_STATUS, result files, status
// lines and exit codes — reports exactly one SlaveState, mapped from here:
//
//   state          meaning                                             LCM  file / line    exit
//   initialising   no usable estimate yet: too few (independent)      0    initialising   3
//                  motions, the motions do not determine the
//                  parameters, or the data do not support the
//                  estimate (residuals beyond the measured noise,
//                  unrelated trajectories, a model the data
//                  contradict; calib/src/batch/batch_acceptance.h)
//   usable         an estimate the data support; its σ has not settled 1    usable         0
//                  (online) or could not be computed (batch)
//   converged      usable, and σ has settled: below the thresholds and 2    converged      0
//                  stable over the last keyframes (online), computed
//                  from the covariance (batch); never with an unknown
//                  (NaN) σ
//   decalibrated   the rig moved: the estimate no longer fits the      3    decalibrated   3
//                  recent motions (online only); it re-converges
//
// The LCM constants slave_extrinsics_t::STATE_* carry the same numbers (checked at compile time
// in rigcal_lcm). What the motion determines is a separate set of facts, never a state: the
// purely translational model (C unobservable), planar motion (C along the axis unobservable,
// or taken from the nominal mounting), and whether a value comes from the non-linear
// refinement.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rigcal {

enum class SlaveState : uint8_t {
  kInitialising = 0,
  kUsable = 1,
  kConverged = 2,
  kDecalibrated = 3,
};

// "initialising", "usable", "converged", "decalibrated".
std::string_view ToString(SlaveState state);

// Facts about a slave's published estimate (bitmask): what the motion determines, and where the
// value comes from. How far the estimate has got is not a fact but its state.
enum SlaveFlags : uint32_t {
  kFlagTranslationalOnly = 1u << 0,  // rotation and scale only (thesis 4.5)
  kFlagPlanar = 1u << 1,             // C along the rotation axis is unobservable
  kFlagRefined = 1u << 2,  // the published value comes from the non-linear window refinement
};

// The words of the facts set in `facts`, in this order: "translational-only", "planar",
// "refined". The one place these words are spelt (status lines, `rigcal status`, the report).
std::vector<std::string_view> FactNames(uint32_t facts);

// A slave's state and facts as words for status lines: the state's name, then FactNames
// ("converged planar refined").
std::string StateText(SlaveState state, uint32_t facts);

// Whether the estimate may be used: usable or converged.
constexpr bool IsUsable(SlaveState state) {
  return state == SlaveState::kUsable || state == SlaveState::kConverged;
}

// The state of a whole rig, for RIGCAL_STATUS and status lines (the LCM constants
// rig_status_t::ESTIMATOR_* carry the same numbers):
//   idle          no slave has seen a motion yet
//   initialising  no slave is usable yet
//   degraded      some slaves usable, some not (the message says which)
//   usable        every slave usable, not every one converged
//   converged     every slave converged
//   decalibrated  some slave decalibrated
enum class RigState : uint8_t {
  kIdle = 0,
  kInitialising = 1,
  kDegraded = 2,
  kUsable = 3,
  kConverged = 4,
  kDecalibrated = 5,
};

std::string_view ToString(RigState state);

// The rig's state from its slaves' (`any_motion`: some slave has seen a motion).
RigState CombineStates(const std::vector<SlaveState>& slaves, bool any_motion);

// Exit code of a command that produced these slaves: 0 when every one is usable, 3 otherwise
// (docs/commands.md "Exit codes": 1 bad input and 2 usage are decided before any estimate exists).
int ExitCodeFor(const std::vector<SlaveState>& slaves);

}  // namespace rigcal
