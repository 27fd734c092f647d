// SPDX-License-Identifier: Apache-2.0
// Exit codes shared by the rigcal subcommands, and their error line.
#pragma once

#include <string_view>

namespace rigcal::cli {

inline constexpr int kExitOk = 0;
inline constexpr int kExitError = 1;

// Prints "rigcal <command>: <message>" on stderr; returns kExitError.
int PrintCommandError(std::string_view command, std::string_view message);

}  // namespace rigcal::cli
