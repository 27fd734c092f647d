// SPDX-License-Identifier: Apache-2.0
#pragma once
// One named spdlog logger per module ("calib", "tools", ...), all writing to stderr.
// The level comes from SetLogLevel (the command line's --log-level) or, before that, from the
// environment variable RIGCAL_LOG_LEVEL (trace, debug, info, warn, error, off).
// Both functions may be called from any thread.

#include <spdlog/spdlog.h>

#include <memory>
#include <string>

namespace rigcal {

std::shared_ptr<spdlog::logger> ModuleLogger(const std::string& module);

// Sets the level of every module logger, present and future. Returns false (and leaves the
// level unchanged) for an unknown level name.
bool SetLogLevel(const std::string& level);

}  // namespace rigcal
