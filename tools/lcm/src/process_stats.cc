// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/process_stats.h"

#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace rigcal::lcm {

int64_t ResidentSetBytes() {
  std::ifstream statm("/proc/self/statm");
  int64_t size_pages = 0;
  int64_t resident_pages = 0;
  if (!(statm >> size_pages >> resident_pages)) return 0;
  return resident_pages * static_cast<int64_t>(sysconf(_SC_PAGESIZE));
}

double ProcessCpuSeconds() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  auto seconds = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * t.tv_usec; };
  return seconds(usage.ru_utime) + seconds(usage.ru_stime);
}

CpuMeter::CpuMeter()
    : last_cpu_s_(ProcessCpuSeconds()), last_wall_(std::chrono::steady_clock::now()) {}

double CpuMeter::Sample() {
  const double cpu_s = ProcessCpuSeconds();
  const auto wall = std::chrono::steady_clock::now();
  const double wall_s = std::chrono::duration<double>(wall - last_wall_).count();
  const double percent = wall_s > 0.0 ? 100.0 * (cpu_s - last_cpu_s_) / wall_s : 0.0;
  last_cpu_s_ = cpu_s;
  last_wall_ = wall;
  return percent < 0.0 ? 0.0 : percent;
}

}  // namespace rigcal::lcm
