// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated rig of one of the shipped configs (config/<file>), not paced in real time, for
// the sim tests that render the rigs users run.

#include <gtest/gtest.h>

#include <string>
#include <utility>

#include "rigcal/io/rig_config.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::sim::testing {

// The rig of config/<file> (its `source: {type: simulated}`) with realtime off. A config that
// does not load or build fails the calling test.
inline SimulatedRig LoadShippedSimulatedRig(const std::string& file) {
  auto config = io::LoadRigConfig(std::string(RIGCAL_SOURCE_DIR) + "/config/" + file);
  EXPECT_TRUE(config.ok()) << config.error();
  SimulatedRigSpec spec = *config->simulated_source;
  spec.realtime = false;
  auto rig = MakeSimulatedRig(spec);
  EXPECT_TRUE(rig.ok()) << rig.error();
  return std::move(rig).value();
}

}  // namespace rigcal::sim::testing
