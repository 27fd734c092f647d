// SPDX-License-Identifier: Apache-2.0
#pragma once
// The truth of solve, calib and replay: io/truth_files.h (shared with `rigcal report`).

#include "rigcal/io/truth_files.h"

namespace rigcal::cli {

using io::CompareRunWithTruth;
using io::ReadTruthFiles;
using io::TruthFiles;

}  // namespace rigcal::cli
