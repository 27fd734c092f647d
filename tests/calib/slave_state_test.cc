// SPDX-License-Identifier: Apache-2.0
// One meaning per state: names, the rig's combined state and the exit code.
#include "rigcal/calib/slave_state.h"

#include <gtest/gtest.h>

namespace rigcal {
namespace {

using S = SlaveState;

TEST(SlaveState, Names) {
  EXPECT_EQ(ToString(S::kInitialising), "initialising");
  EXPECT_EQ(ToString(S::kUsable), "usable");
  EXPECT_EQ(ToString(S::kConverged), "converged");
  EXPECT_EQ(ToString(S::kDecalibrated), "decalibrated");
  EXPECT_EQ(ToString(RigState::kDegraded), "degraded");
}

TEST(SlaveState, UsableMeansUsableOrConverged) {
  EXPECT_FALSE(IsUsable(S::kInitialising));
  EXPECT_TRUE(IsUsable(S::kUsable));
  EXPECT_TRUE(IsUsable(S::kConverged));
  EXPECT_FALSE(IsUsable(S::kDecalibrated));
}

TEST(SlaveState, RigStateIsTheWeakestSlave) {
  EXPECT_EQ(CombineStates({}, false), RigState::kIdle);
  EXPECT_EQ(CombineStates({S::kInitialising, S::kInitialising}, false), RigState::kIdle);
  EXPECT_EQ(CombineStates({S::kInitialising, S::kInitialising}, true), RigState::kInitialising);
  EXPECT_EQ(CombineStates({S::kConverged, S::kInitialising}, true), RigState::kDegraded);
  EXPECT_EQ(CombineStates({S::kConverged, S::kUsable}, true), RigState::kUsable);
  EXPECT_EQ(CombineStates({S::kConverged, S::kConverged}, true), RigState::kConverged);
  EXPECT_EQ(CombineStates({S::kConverged, S::kDecalibrated}, true), RigState::kDecalibrated);
}

TEST(SlaveState, ExitCodeThreeUnlessEverySlaveIsUsable) {
  EXPECT_EQ(ExitCodeFor({S::kConverged, S::kUsable}), 0);
  EXPECT_EQ(ExitCodeFor({S::kConverged, S::kInitialising}), 3);
  EXPECT_EQ(ExitCodeFor({S::kDecalibrated}), 3);
  EXPECT_EQ(ExitCodeFor({}), 3);
}

TEST(SlaveState, FactsAsWords) {
  EXPECT_EQ(StateText(SlaveState::kConverged, kFlagPlanar), "converged planar");
  EXPECT_EQ(StateText(SlaveState::kUsable, 0), "usable");
  EXPECT_EQ(StateText(SlaveState::kDecalibrated, kFlagTranslationalOnly | kFlagRefined),
            "decalibrated translational-only refined");
  EXPECT_EQ(FactNames(kFlagRefined | kFlagPlanar),
            (std::vector<std::string_view>{"planar", "refined"}));
  EXPECT_TRUE(FactNames(0).empty());
}

}  // namespace
}  // namespace rigcal
