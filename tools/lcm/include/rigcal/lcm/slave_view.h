// SPDX-License-Identifier: Apache-2.0
#pragma once
// A slave_extrinsics_t as the calib types see it: its orientation as a quaternion, its state as
// a SlaveState, and its flags as the words status lines use for the facts.

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "rigcal/calib/slave_state.h"
#include "rigcal/slave_extrinsics_t.hpp"

namespace rigcal::lcm {

struct SlaveView {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // master_from_slave
  SlaveState state = SlaveState::kInitialising;           // an undefined state reads as this
  // FactNames of the wire flags (slave_state.h: "translational-only", "planar", "refined"),
  // then "axis-from-prior".
  std::vector<std::string> facts;
};

SlaveView ViewOf(const slave_extrinsics_t& slave);

}  // namespace rigcal::lcm
