// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated two-camera rig the loopback tests feed through v4l2loopback
// (scripts/vm/guest-init.sh: /dev/video20 and /dev/video21): its config with the simulated
// source, and the same cameras captured from the loopback devices (GREY and YUYV).

#include <string>

#include "support/loopback_rig_yaml.h"

namespace rigcal::device_test {

using support::kLoopbackDriveS;
using support::SimulatedLoopbackRigYaml;  // seed 3

// The cameras of `simulated` captured from /dev/video20 (GREY) and /dev/video21 (YUYV), with the
// stream-time settings of a writer feeding about a frame a second under emulation.
std::string V4l2LoopbackRigYaml(const std::string& simulated);

}  // namespace rigcal::device_test
