// SPDX-License-Identifier: Apache-2.0
// Soak: the drive of surround_drive_load_test for 1 hour of drive time (label soak, not in make
// test: `ctest --test-dir build -L soak -V`), at RIGCAL_SOAK_SPEED times real time (default 10:
// 6 minutes), with the default pose history (10000 sets per slave, full after 500 s).
#include <gtest/gtest.h>

#include <cstdlib>

#include "surround_drive.h"
#include "surround_drive_checks.h"

namespace rigcal::pipeline::surround_drive {
namespace {

TEST(SurroundDriveSoak, OneHourStaysFlatAndRight) {
  const char* env = std::getenv("RIGCAL_SOAK_SPEED");
  const double speed = env != nullptr ? std::atof(env) : 10.0;
  ASSERT_GT(speed, 0.0) << "RIGCAL_SOAK_SPEED";
  const Report report = Drive(/*drive_s=*/3600.0, speed, /*history_sets=*/10000);
  CheckDrive(report, /*flat_after_s=*/900.0);
}

}  // namespace
}  // namespace rigcal::pipeline::surround_drive
