// SPDX-License-Identifier: Apache-2.0
#pragma once
// CPU and memory use of this process, for RIGCAL_STATUS and the live status line (Linux /proc).

#include <chrono>
#include <cstdint>

namespace rigcal::lcm {

// Resident set size in bytes (/proc/self/statm), 0 when unavailable.
int64_t ResidentSetBytes();

// CPU time of the process (user + system), seconds, from getrusage.
double ProcessCpuSeconds();

// CPU use between successive calls of Sample(): 100 = one core busy.
class CpuMeter {
 public:
  CpuMeter();
  // Percent since the previous call (or construction). Not thread-safe.
  double Sample();

 private:
  double last_cpu_s_;
  std::chrono::steady_clock::time_point last_wall_;
};

}  // namespace rigcal::lcm
