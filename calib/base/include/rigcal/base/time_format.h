// SPDX-License-Identifier: Apache-2.0
#pragma once
// Time stamps as text, the same way everywhere (files, messages).

#include <cstdint>
#include <string>

namespace rigcal {

// Nanoseconds as seconds with exactly 9 decimals, no rounding, for every int64 (INT64_MIN
// included): "1403715524.907143168", "-0.000000001". ParseSecondsToNs (rigcal_io) reads it back.
std::string FormatNsAsSeconds(int64_t t_ns);

}  // namespace rigcal
