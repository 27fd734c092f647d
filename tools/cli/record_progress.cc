// SPDX-License-Identifier: Apache-2.0
#include "record_progress.h"

#include <cstdio>

namespace rigcal::cli {
namespace {

constexpr char kProgressPrefix[] = "rigcal record: ";

// "  12.0 s | 86.4 MB (7.2 MB/s) | frames 240 240 | drops 0 | 1 file".
std::string ProgressText(double elapsed_s, const pipeline::RecorderStats& s) {
  char buf[256];
  const double mb = static_cast<double>(s.bytes) / 1e6;
  std::snprintf(buf, sizeof(buf), "%7.1f s | %8.1f MB (%.1f MB/s) | frames", elapsed_s, mb,
                elapsed_s > 0 ? mb / elapsed_s : 0.0);
  std::string line = buf;
  for (int64_t n : s.frames) line += " " + std::to_string(n);
  std::snprintf(buf, sizeof(buf), " | drops %lld", static_cast<long long>(s.DroppedTotal()));
  line += buf;
  if (s.DroppedTotal() > 0) {
    line += " (disk " + std::to_string(s.dropped_disk) + ", cameras";
    for (int64_t n : s.dropped_capture) line += " " + std::to_string(n);
    line += ")";
  }
  if (s.other_events > 0) line += " | poses+extrinsics " + std::to_string(s.other_events);
  line += " | " + std::to_string(s.files.size()) + (s.files.size() == 1 ? " file" : " files");
  return line;
}

}  // namespace

RecordProgress::RecordProgress()
    : start_(std::chrono::steady_clock::now()), last_(start_) {}

double RecordProgress::elapsed_s() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void RecordProgress::Update(const pipeline::RecorderStats& stats, bool force) {
  const auto now = std::chrono::steady_clock::now();
  const double period_s = line_.tty() ? 0.25 : 1.0;
  if (!force && std::chrono::duration<double>(now - last_).count() < period_s) return;
  last_ = now;
  line_.Show(std::string(kProgressPrefix) + ProgressText(elapsed_s(), stats), force);
}

void RecordProgress::End() {}

void PrintRecordingSummary(const pipeline::RecorderStats& stats, double elapsed_s,
                           double cpu_percent) {
  const double mb = static_cast<double>(stats.bytes) / 1e6;
  std::printf(
      "recorded %lld frames (%lld events, %.1f MB) in %.1f s to %zu file%s: %.2f MB/s, %.1f "
      "frames/s, CPU %.0f %% (100 = one core), dropped %lld\n",
      static_cast<long long>(stats.FramesTotal()), static_cast<long long>(stats.events), mb,
      elapsed_s, stats.files.size(), stats.files.size() == 1 ? "" : "s", mb / elapsed_s,
      static_cast<double>(stats.FramesTotal()) / elapsed_s, cpu_percent,
      static_cast<long long>(stats.DroppedTotal()));
  for (const std::string& file : stats.files) std::printf("  %s\n", file.c_str());
}

}  // namespace rigcal::cli
