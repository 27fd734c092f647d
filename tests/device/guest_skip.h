// SPDX-License-Identifier: Apache-2.0
#pragma once
// The device tests run inside the QEMU guest of scripts/vm/run-device-tests.sh, where the
// drivers are loaded. Elsewhere (no such node) they skip with the reason.

#include <unistd.h>

#include <string>

#include "support/skip.h"

#define RIGCAL_REQUIRE_NODE(path)                                                    \
  do {                                                                               \
    if (access(path, F_OK) != 0) {                                                   \
      RIGCAL_SKIP_MISSING() << path << " does not exist (run inside the device VM: " \
                            << "scripts/vm/run-device-tests.sh)";                    \
    }                                                                                \
  } while (0)
