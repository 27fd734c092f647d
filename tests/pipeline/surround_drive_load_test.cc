// SPDX-License-Identifier: Apache-2.0
// Load: a 2-minute simulated drive of the 4-camera car rig through the calibration node at 10x
// real time (pose level, tests/pipeline/surround_drive.h), with a camera that dies at 60 % and
// one that loses track every 20 s. Memory and queues stay flat (slopes printed), every pose is
// accounted for by cause, the estimate does not diverge, the status names the dead camera, and
// the CPU of every stage is printed. The 1-hour drive is surround_drive_soak_test (label soak).
#include <gtest/gtest.h>

#include <iostream>

#include "surround_drive.h"
#include "surround_drive_checks.h"

namespace rigcal::pipeline::surround_drive {
namespace {

TEST(SurroundDriveLoad, TwoMinutesStayFlatAndRight) {
  // A pose history of 1000 sets per slave (50 s) fills within the first half of the drive, so
  // that the second half shows whether anything else grows.
  const Report report = Drive(/*drive_s=*/120.0, /*speed=*/10.0, /*history_sets=*/1000);
  CheckDrive(report, /*flat_after_s=*/60.0);
}

}  // namespace
}  // namespace rigcal::pipeline::surround_drive
