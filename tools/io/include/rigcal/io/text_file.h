// SPDX-License-Identifier: Apache-2.0
#pragma once
// Reading a whole (text) file: configs, states, results.

#include <string>

#include "rigcal/base/status.h"

namespace rigcal::io {

// The whole file as text; the error names the path and errno text.
Expected<std::string> ReadWholeFile(const std::string& path);

}  // namespace rigcal::io
